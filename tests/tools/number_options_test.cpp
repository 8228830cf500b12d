// The number options of the host tools' CLI11 parsers (tools/args/number_options.hpp): values
// read as the hand-written parsers read them (base 10, strtod), refusals that name the option.
// References: the compiler's own reading of decimal literals, and exact binary fractions.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "number_options.hpp"
#include "parse_args.hpp"

namespace {

using ccmap::tools::parse_real;
using ccmap::tools::parse_whole;

/// The message of the CLI::ValidationError `f` throws, or "" if it throws none.
template <typename F>
std::string refusal(F f) {
  try {
    f();
  } catch (const CLI::ValidationError& e) {
    return e.what();
  }
  return "";
}

TEST(NumberOptions, WholeNumbersAreBaseTen) {
  // CLI11 2.1 reads INT with base 0, where "010" is 8 and "0x10" is 16.
  EXPECT_EQ(parse_whole<int>("--stride", "010", 1, 100), 10) << "a leading zero must not make the value octal";
  EXPECT_EQ(parse_whole<int>("--stride", "+7", 1, 100), 7);
  EXPECT_EQ(parse_whole<std::uint64_t>("--seed", "18446744073709551615", 0, UINT64_MAX), UINT64_MAX);
  EXPECT_EQ(parse_whole<int>("--finest", "-3", -5, 5), -3);
  for (const char* bad : {"0x10", "", " 5", "5 ", "1.5", "1e3", "abc", "+", "-"}) {
    EXPECT_EQ(refusal([&] { (void)parse_whole<int>("--stride", bad, 1, 100); }),
              "--stride: '" + std::string(bad) + "' is not a whole number")
        << "'" << bad << "' was accepted as a whole number";
  }
}

TEST(NumberOptions, WholeNumbersOutsideTheRangeAreRefused) {
  EXPECT_EQ(refusal([] { (void)parse_whole<int>("--stride", "0", 1, 650); }),
            "--stride: 0 is out of range (expected a whole number 1 .. 650)");
  EXPECT_EQ(refusal([] { (void)parse_whole<int>("--stride", "651", 1, 650); }),
            "--stride: 651 is out of range (expected a whole number 1 .. 650)");
  // An unsigned value with a sign is not wrapped around (strtoull reads "-1" as 2^64 - 1).
  EXPECT_NE(refusal([] { (void)parse_whole<std::uint64_t>("--seed", "-1", 0, UINT64_MAX); }), "");
  // Beyond the 64-bit type itself (strtoull saturates and sets ERANGE).
  EXPECT_NE(refusal([] { (void)parse_whole<std::uint64_t>("--seed", "18446744073709551616", 0, UINT64_MAX); }), "");
  EXPECT_NE(refusal([] { (void)parse_whole<int>("--frames", "99999999999", 1, INT32_MAX); }), "");
}

TEST(NumberOptions, RealNumbersAreReadStraightIntoADouble) {
  EXPECT_EQ(parse_real("--spacing", "0.3", 0.0, 1e9, true), 0.3);
  EXPECT_EQ(parse_real("--odometry-sigma", "5e-2", 0.0, 1.0), 0.05);
  // 1 + 2^-53 + 2^-70, written out exactly: the nearest double is 1 + 2^-52. Read through an
  // x86 long double (64-bit mantissa, what CLI11 2.1's strtold does) it first rounds to
  // 1 + 2^-53, the tie between 1 and 1 + 2^-52, which then goes to the even 1.
  const std::string tie_breaker = "1.0000000000000001110231494954629083427022351315827108919620513916015625";
  EXPECT_EQ(parse_real("--spacing", tie_breaker, 0.0, 10.0), std::nextafter(1.0, 2.0))
      << "the value was rounded twice";
}

TEST(NumberOptions, RealNumbersOutsideTheRangeAreRefused) {
  EXPECT_EQ(refusal([] { (void)parse_real("--spacing", "0", 0.0, 1e9, true); }),
            "--spacing: 0 is out of range (expected a number in (0, 1e+09])");
  EXPECT_EQ(refusal([] { (void)parse_real("--odometry-sigma", "1.5", 0.0, 1.0); }),
            "--odometry-sigma: 1.5 is out of range (expected a number in [0, 1])");
  EXPECT_EQ(parse_real("--odometry-sigma", "0", 0.0, 1.0), 0.0) << "the closed end of the range was refused";
  EXPECT_EQ(parse_real("--odometry-sigma", "1", 0.0, 1.0), 1.0) << "the closed end of the range was refused";
  // CLI::Range lets NaN through (every comparison with NaN is false); these must not.
  for (const char* bad : {"nan", "NAN", "-nan", "inf", "-inf", "1e400"}) {
    EXPECT_NE(refusal([&] { (void)parse_real("--floor", bad, 0.0, 1e6); }), "") << bad << " was accepted";
  }
  for (const char* bad : {"", " 1", "1 ", "x", "1,5", "0.5m"}) {
    EXPECT_EQ(refusal([&] { (void)parse_real("--floor", bad, 0.0, 1e6); }),
              "--floor: '" + std::string(bad) + "' is not a number");
  }
}

TEST(NumberOptions, OptionsStoreTheValueAndRefuseThroughParseArgs) {
  int stride = 2;
  double spacing = 0.3;
  CLI::App app("test", "number_options_test");
  ccmap::tools::add_whole(app, "--stride", &stride, 1, 650, "K", "pixel stride");
  ccmap::tools::add_real(app, "--spacing", &spacing, 0.0, 1e9, true, "M", "metres");
  EXPECT_NE(app.help().find("--stride K=2"), std::string::npos) << app.help();
  EXPECT_NE(app.help().find("--spacing M=0.3"), std::string::npos) << app.help();
  std::vector<std::string> args{"number_options_test", "--stride", "010", "--spacing", "0.25"};
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  EXPECT_EQ(ccmap::tools::parse_args(app, static_cast<int>(argv.size()), argv.data()), -1);
  EXPECT_EQ(stride, 10);
  EXPECT_EQ(spacing, 0.25);
}

}  // namespace
