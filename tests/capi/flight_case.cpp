// Registers the flight-interface test (flight_test.c, plain C99) as one case of the portable harness.
#include "harness.hpp"

extern "C" void ccmap_flight_test(void);

BM_CASE(capi, flight_interface) { ccmap_flight_test(); }
