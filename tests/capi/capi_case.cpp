// Registers the C API test (capi_test.c, plain C99) as one case of the portable harness.
#include "harness.hpp"

extern "C" void ccmap_capi_test(void);

BM_CASE(capi, c_program) { ccmap_capi_test(); }
