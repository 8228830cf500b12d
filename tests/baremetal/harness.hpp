// Portable test harness: the library tests that must also run on bare metal, where GoogleTest
// does not (it needs the heap, exceptions and a POSIX C library: docs/integration.md).
//
// A case is a function registered with BM_CASE(group, name) (a static registrar: a linked list,
// no heap). run() executes the cases whose "group.name" starts with one of the given prefixes,
// prints "[ RUN  ] / [  OK  ] / [ FAIL ]" lines and "N passed, N failed (M checks)", and returns
// the exit code: 0 if every selected case passed, 1 if one failed, 2 if no case was selected
// (a misspelt filter must not pass). Checks report file:line and a message in domain terms.
//
// Output goes through ccmap_test_write (harness.h); numbers are printed with integer
// arithmetic and float operations only (no double: the board image must not contain a
// soft-double helper, tests/baremetal/check_image.cmake).
#pragma once

#include <cstddef>
#include <cstdint>

#include "ccmap/core/status.hpp"
#include "harness.h"

namespace ccmap::bmtest {

using CaseFunction = void (*)();

struct Case {
  const char* group;
  const char* name;
  CaseFunction function;
  Case* next;
};

/// Appends `c` to the registry (in registration order).
struct Registrar {
  explicit Registrar(Case& c) noexcept;
};

/// A line of output built in a fixed buffer (truncated at 255 characters), written by end().
class Line {
 public:
  Line& text(const char* s) noexcept;
  Line& u64(std::uint64_t v) noexcept;
  Line& i64(std::int64_t v) noexcept;
  Line& hex32(std::uint32_t v) noexcept;  ///< 0x + 8 digits
  Line& hex64(std::uint64_t v) noexcept;  ///< 16 digits, no prefix (the golden-file format)
  /// Approximately (7 significant digits, float arithmetic), then the exact bits: 1.250000e-01 [0x3e000000].
  Line& f32(float v) noexcept;
  /// value / scale with `decimals` digits (integer arithmetic): fixed(12345, 1000, 2) = "12.34".
  Line& fixed(std::uint64_t value, std::uint64_t scale, int decimals) noexcept;
  void end() noexcept;

 private:
  Line& hex_digits(std::uint64_t v, int digits) noexcept;  ///< the low `digits` (<= 16) hex digits
  char buffer_[256] = {};
  std::size_t size_ = 0;
};

/// Runs the selected cases. `filter`: space-separated prefixes of "group.name"; empty = all.
[[nodiscard]] int run(const char* filter) noexcept;

/// Checks with a location (the BM_ macros fill it in). Each returns whether it held.
bool check(bool ok, const char* file, int line, const char* what) noexcept;
bool check_near(float actual, float expected, float tolerance, const char* file, int line, const char* what) noexcept;
bool check_equal(std::uint64_t actual, std::uint64_t expected, const char* file, int line, const char* what) noexcept;

/// Bits of a float (for bitwise comparisons without -Wfloat-equal).
[[nodiscard]] std::uint32_t bits(float v) noexcept;

}  // namespace ccmap::bmtest

#define BM_CASE(group, name)                                                                    \
  static void bm_case_##group##_##name();                                                       \
  static ::ccmap::bmtest::Case bm_case_record_##group##_##name{#group, #name,                   \
                                                               &bm_case_##group##_##name, nullptr}; \
  static const ::ccmap::bmtest::Registrar bm_case_registrar_##group##_##name{bm_case_record_##group##_##name}; \
  static void bm_case_##group##_##name()

#define BM_CHECK(condition, what) ::ccmap::bmtest::check((condition), __FILE__, __LINE__, what)
#define BM_CHECK_NEAR(actual, expected, tolerance, what) \
  ::ccmap::bmtest::check_near((actual), (expected), (tolerance), __FILE__, __LINE__, what)
#define BM_CHECK_EQ(actual, expected, what)                                                       \
  ::ccmap::bmtest::check_equal(static_cast<std::uint64_t>(actual), static_cast<std::uint64_t>(expected), \
                               __FILE__, __LINE__, what)
#define BM_CHECK_STATUS(actual, expected, what)                                                  \
  ::ccmap::bmtest::check_texts_status((actual), (expected), __FILE__, __LINE__, what)

namespace ccmap::bmtest {
/// actual == expected, printing both status names.
inline bool check_texts_status(Status actual, Status expected, const char* file, int line, const char* what) noexcept {
  return ccmap_test_check_texts(actual == expected ? 1 : 0, file, line, what, to_string(actual),
                                to_string(expected)) != 0;
}
}  // namespace ccmap::bmtest
