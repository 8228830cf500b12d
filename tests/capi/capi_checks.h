/* The checks of the C API tests (capi_test.c, flight_test.c) over the portable harness's C face
 * (tests/baremetal/harness.h): a failed one prints file:line and what was expected. */
#ifndef CCMAP_TESTS_CAPI_CHECKS_H
#define CCMAP_TESTS_CAPI_CHECKS_H

#include "ccmap/ccmap.h"
#include "harness.h"

#define CHECK(cond) ccmap_test_check((cond) ? 1 : 0, __FILE__, __LINE__, #cond)

#define CHECK_STATUS(expr, expected)                                                          \
  do {                                                                                        \
    const ccmap_status got_ = (expr);                                                         \
    ccmap_test_check_texts(got_ == (expected), __FILE__, __LINE__, #expr,                     \
                           ccmap_status_string(got_), ccmap_status_string(expected));         \
  } while (0)

#define CHECK_NEAR(a, b, tol) ccmap_test_check_near((float)(a), (float)(b), (float)(tol), __FILE__, __LINE__, #a)

#define CHECK_EQ(a, b) ccmap_test_check_equal((int64_t)(a), (int64_t)(b), __FILE__, __LINE__, #a " == " #b)

#endif /* CCMAP_TESTS_CAPI_CHECKS_H */
