// Whole-number command-line arguments of the test and example programs (tests/icount).
#pragma once

#include <cstdlib>

namespace ccmap::test {

/// Parses `text` as a whole number in [1, max] into *value; false (nothing written) otherwise.
inline bool parse_count(const char* text, int max, int* value) {
  char* end = nullptr;
  const long v = std::strtol(text, &end, 10);
  if (end == text || *end != '\0' || v < 1 || v > max) {
    return false;
  }
  *value = static_cast<int>(v);
  return true;
}

}  // namespace ccmap::test
