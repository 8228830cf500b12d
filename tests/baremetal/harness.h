/* The C face of the portable test harness (harness.hpp): what C test files (tests/capi/
 * capi_test.c) call. Every check counts; a failed one prints file:line and the message and marks
 * the running case failed. No allocation, no stdio, no double: the same file runs on the host,
 * on aarch64 Linux and on the bare-metal board. */
#ifndef CCMAP_TESTS_BAREMETAL_HARNESS_H
#define CCMAP_TESTS_BAREMETAL_HARNESS_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Returns ok. */
int ccmap_test_check(int ok, const char* file, int line, const char* what);
/* |actual - expected| <= tolerance (NaN fails). Returns whether it held. */
int ccmap_test_check_near(float actual, float expected, float tolerance, const char* file, int line,
                          const char* what);
/* actual == expected. */
int ccmap_test_check_equal(int64_t actual, int64_t expected, const char* file, int line, const char* what);
/* ok, or a failure showing two texts ("got", "expected"). */
int ccmap_test_check_texts(int ok, const char* file, int line, const char* what, const char* got,
                           const char* expected);
/* One line of output ("text\n"). */
void ccmap_test_note(const char* text);

/* The output sink: host stdout (sink_host.cpp) or the board's semihosting (sink_board.cpp). */
void ccmap_test_write(const char* text);

#ifdef __cplusplus
}
#endif

#endif /* CCMAP_TESTS_BAREMETAL_HARNESS_H */
