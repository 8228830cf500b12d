// Number options for CLI11 parsers (tools/args/parse_args.hpp) that read their values as the
// hand-written parsers before them did, so that the same command line gives the same numbers:
//  - whole numbers in base 10 (CLI11 2.1 reads INT with base 0: "010" would be 8, "0x10" 16);
//  - real numbers with strtod straight into a double (CLI11 2.1 reads FLOAT with strtold and
//    rounds the long double again to double);
//  - a range check that refuses NaN (CLI::Range lets "nan" through: every comparison with NaN
//    is false).
// A refusal is a CLI::ValidationError that names the option and the value, e.g.
//   "--stride: 0 is out of range (expected a whole number 1 .. 1000000000)".
#pragma once

#include <CLI/CLI.hpp>

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <type_traits>

namespace ccmap::tools {

/// `text` as a base-10 whole number in [lo, hi]: an optional sign ('-' only for signed T), then
/// digits and nothing else. Throws CLI::ValidationError naming `option` otherwise.
template <typename T>
T parse_whole(const std::string& option, const std::string& text, T lo, T hi) {
  static_assert(std::is_integral<T>::value && sizeof(T) <= 8, "a whole-number option needs an integer type");
  const std::size_t digits = (!text.empty() && (text[0] == '+' || text[0] == '-')) ? 1 : 0;
  bool ok = text.size() > digits;
  for (std::size_t i = digits; ok && i < text.size(); ++i) ok = std::isdigit(static_cast<unsigned char>(text[i])) != 0;
  if (!ok) throw CLI::ValidationError(option, "'" + text + "' is not a whole number");
  const std::string range = " is out of range (expected a whole number " + std::to_string(lo) + " .. " +
                            std::to_string(hi) + ")";
  errno = 0;
  if constexpr (std::is_signed<T>::value) {
    const long long v = std::strtoll(text.c_str(), nullptr, 10);
    if (errno == ERANGE || v < static_cast<long long>(lo) || v > static_cast<long long>(hi)) {
      throw CLI::ValidationError(option, text + range);
    }
    return static_cast<T>(v);
  } else {
    const unsigned long long v = std::strtoull(text.c_str(), nullptr, 10);
    if (text[0] == '-' || errno == ERANGE || v < static_cast<unsigned long long>(lo) ||
        v > static_cast<unsigned long long>(hi)) {
      throw CLI::ValidationError(option, text + range);
    }
    return static_cast<T>(v);
  }
}

/// `text` as a finite number (strtod, the whole text) in [lo, hi], or in (lo, hi] when
/// `exclude_lo`. Throws CLI::ValidationError naming `option` otherwise.
inline double parse_real(const std::string& option, const std::string& text, double lo, double hi,
                         bool exclude_lo = false) {
  char* end = nullptr;
  const double v = text.empty() || std::isspace(static_cast<unsigned char>(text[0])) != 0
                       ? 0.0
                       : std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size() || text.empty()) {
    throw CLI::ValidationError(option, "'" + text + "' is not a number");
  }
  if (!std::isfinite(v) || (exclude_lo ? !(v > lo) : !(v >= lo)) || !(v <= hi)) {
    char expected[96];
    std::snprintf(expected, sizeof expected, "%c%g, %g]", exclude_lo ? '(' : '[', lo, hi);
    throw CLI::ValidationError(option, text + " is out of range (expected a number in " + expected + ")");
  }
  return v;
}

/// A whole-number option `name` (parse_whole) into *target; the help shows TYPE=<*target>
/// (->default_str("") after it where that default is not a value, e.g. "0: no limit").
template <typename T>
CLI::Option* add_whole(CLI::App& app, const std::string& name, T* target, T lo, T hi, const std::string& type,
                       const std::string& help) {
  return app
      .add_option_function<std::string>(
          name, [name, target, lo, hi](const std::string& v) { *target = parse_whole(name, v, lo, hi); }, help)
      ->type_name(type)
      ->default_str(std::to_string(*target));
}

/// A real-number option `name` (parse_real) into *target; the help shows TYPE=<*target> (%g).
inline CLI::Option* add_real(CLI::App& app, const std::string& name, double* target, double lo, double hi,
                             bool exclude_lo, const std::string& type, const std::string& help) {
  char shown[32];
  std::snprintf(shown, sizeof shown, "%g", *target);
  return app
      .add_option_function<std::string>(
          name,
          [name, target, lo, hi, exclude_lo](const std::string& v) { *target = parse_real(name, v, lo, hi, exclude_lo); },
          help)
      ->type_name(type)
      ->default_str(shown);
}

}  // namespace ccmap::tools
