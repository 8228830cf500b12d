#include "harness.hpp"

#include <cstring>

namespace ccmap::bmtest {
namespace {

Case* g_first = nullptr;
Case* g_last = nullptr;
const Case* g_current = nullptr;
bool g_current_failed = false;
std::uint64_t g_checks = 0U;

void fail_header(const char* file, int line, Line& out) noexcept {
  g_current_failed = true;
  out.text("  ").text(file != nullptr ? file : "?").text(":").i64(line).text(": ");
}

/// True if "group.name" starts with `prefix` (length n).
bool matches(const Case& c, const char* prefix, std::size_t n) noexcept {
  const std::size_t group_length = std::strlen(c.group);
  if (n <= group_length) {
    return std::strncmp(c.group, prefix, n) == 0;
  }
  if (std::strncmp(c.group, prefix, group_length) != 0 || prefix[group_length] != '.') {
    return false;
  }
  return std::strncmp(c.name, prefix + group_length + 1U, n - group_length - 1U) == 0;
}

bool selected(const Case& c, const char* filter) noexcept {
  bool any = false;
  for (const char* p = filter; *p != '\0';) {
    while (*p == ' ') {
      ++p;
    }
    const char* end = p;
    while (*end != '\0' && *end != ' ') {
      ++end;
    }
    if (end > p) {
      any = true;
      if (matches(c, p, static_cast<std::size_t>(end - p))) {
        return true;
      }
    }
    p = end;
  }
  return !any;
}

}  // namespace

Registrar::Registrar(Case& c) noexcept {
  c.next = nullptr;
  if (g_last == nullptr) {
    g_first = &c;
  } else {
    g_last->next = &c;
  }
  g_last = &c;
}

Line& Line::text(const char* s) noexcept {
  for (; s != nullptr && *s != '\0' && size_ + 1U < sizeof buffer_; ++s) {
    buffer_[size_++] = *s;
  }
  buffer_[size_] = '\0';
  return *this;
}

Line& Line::u64(std::uint64_t v) noexcept {
  char digits[21];
  std::size_t n = 0U;
  do {
    digits[n++] = static_cast<char>('0' + v % 10U);
    v /= 10U;
  } while (v != 0U);
  char out[21];
  for (std::size_t i = 0; i < n; ++i) {
    out[i] = digits[n - 1U - i];
  }
  out[n] = '\0';
  return text(out);
}

Line& Line::i64(std::int64_t v) noexcept {
  if (v < 0) {
    text("-");
    return u64(0U - static_cast<std::uint64_t>(v));
  }
  return u64(static_cast<std::uint64_t>(v));
}

Line& Line::hex64(std::uint64_t v) noexcept { return hex_digits(v, 16); }

Line& Line::hex32(std::uint32_t v) noexcept { return text("0x").hex_digits(v, 8); }

Line& Line::hex_digits(std::uint64_t v, int digits) noexcept {
  char out[17];
  for (int i = 0; i < digits; ++i) {
    const auto digit = static_cast<unsigned>((v >> (4 * (digits - 1 - i))) & 0xFU);
    out[i] = static_cast<char>(digit < 10U ? '0' + digit : 'a' + (digit - 10U));
  }
  out[digits] = '\0';
  return text(out);
}

Line& Line::fixed(std::uint64_t value, std::uint64_t scale, int decimals) noexcept {
  if (scale == 0U) {
    return text("?");
  }
  std::uint64_t unit = 1U;
  for (int i = 0; i < decimals; ++i) {
    unit *= 10U;
  }
  // Rounded to `decimals` digits: value / scale * unit, half up.
  const std::uint64_t scaled = (value * unit + scale / 2U) / scale;
  u64(scaled / unit);
  if (decimals > 0) {
    text(".");
    std::uint64_t rest = scaled % unit;
    for (std::uint64_t d = unit / 10U; d > 0U; d /= 10U) {
      const auto digit = static_cast<char>('0' + rest / d);
      const char s[2] = {digit, '\0'};
      text(s);
      rest %= d;
    }
  }
  return *this;
}

Line& Line::f32(float v) noexcept {
  const std::uint32_t b = bits(v);
  if ((b & 0x7F800000U) == 0x7F800000U) {
    text((b & 0x007FFFFFU) != 0U ? "nan" : ((b >> 31U) != 0U ? "-inf" : "inf"));
  } else {
    if ((b >> 31U) != 0U) {
      text("-");
    }
    float a = (b >> 31U) != 0U ? -v : v;
    int exponent = 0;
    if (a > 0.0F) {
      while (a >= 10.0F) {
        a /= 10.0F;
        ++exponent;
      }
      while (a < 1.0F) {
        a *= 10.0F;
        --exponent;
      }
    }
    auto digits = static_cast<std::uint32_t>(a * 1.0e6F + 0.5F);
    if (digits >= 10000000U) {
      digits /= 10U;
      ++exponent;
    }
    fixed(digits, 1000000U, 6).text("e").i64(exponent);
  }
  return text(" [").hex32(b).text("]");
}

void Line::end() noexcept {
  text("\n");
  ccmap_test_write(buffer_);
  size_ = 0U;
  buffer_[0] = '\0';
}

std::uint32_t bits(float v) noexcept {
  std::uint32_t out = 0U;
  std::memcpy(&out, &v, sizeof out);
  return out;
}

bool check(bool ok, const char* file, int line, const char* what) noexcept {
  ++g_checks;
  if (!ok) {
    Line out;
    fail_header(file, line, out);
    out.text(what).end();
  }
  return ok;
}

bool check_near(float actual, float expected, float tolerance, const char* file, int line,
                const char* what) noexcept {
  const float difference = actual > expected ? actual - expected : expected - actual;
  const bool ok = difference <= tolerance;  // false for NaN
  ++g_checks;
  if (!ok) {
    Line out;
    fail_header(file, line, out);
    out.text(what).text(": got ").f32(actual).text(", expected ").f32(expected).text(" +- ").f32(tolerance).end();
  }
  return ok;
}

bool check_equal(std::uint64_t actual, std::uint64_t expected, const char* file, int line, const char* what) noexcept {
  const bool ok = actual == expected;
  ++g_checks;
  if (!ok) {
    Line out;
    fail_header(file, line, out);
    out.text(what).text(": got ").u64(actual).text(" (0x").hex64(actual).text("), expected ").u64(expected);
    out.text(" (0x").hex64(expected).text(")").end();
  }
  return ok;
}

int run(const char* filter) noexcept {
  if (filter == nullptr) {
    filter = "";
  }
  std::uint32_t passed = 0U;
  std::uint32_t failed = 0U;
  for (const Case* c = g_first; c != nullptr; c = c->next) {
    if (!selected(*c, filter)) {
      continue;
    }
    g_current = c;
    g_current_failed = false;
    Line().text("[ RUN  ] ").text(c->group).text(".").text(c->name).end();
    c->function();
    Line().text(g_current_failed ? "[ FAIL ] " : "[  OK  ] ").text(c->group).text(".").text(c->name).end();
    if (g_current_failed) {
      ++failed;
    } else {
      ++passed;
    }
  }
  g_current = nullptr;
  if (passed + failed == 0U) {
    Line().text("no test case matches '").text(filter).text("'").end();
    return 2;
  }
  Line().u64(passed).text(" passed, ").u64(failed).text(" failed (").u64(g_checks).text(" checks)").end();
  return failed == 0U ? 0 : 1;
}

}  // namespace ccmap::bmtest

extern "C" {

int ccmap_test_check(int ok, const char* file, int line, const char* what) {
  return ccmap::bmtest::check(ok != 0, file, line, what) ? 1 : 0;
}

int ccmap_test_check_near(float actual, float expected, float tolerance, const char* file, int line,
                          const char* what) {
  return ccmap::bmtest::check_near(actual, expected, tolerance, file, line, what) ? 1 : 0;
}

int ccmap_test_check_equal(int64_t actual, int64_t expected, const char* file, int line, const char* what) {
  return ccmap::bmtest::check_equal(static_cast<std::uint64_t>(actual), static_cast<std::uint64_t>(expected), file,
                                    line, what)
             ? 1
             : 0;
}

int ccmap_test_check_texts(int ok, const char* file, int line, const char* what, const char* got,
                           const char* expected) {
  if (ok != 0) {
    return ccmap::bmtest::check(true, file, line, what) ? 1 : 0;
  }
  ccmap::bmtest::check(false, file, line, what);
  ccmap::bmtest::Line().text("    got ").text(got).text(", expected ").text(expected).end();
  return 0;
}

void ccmap_test_note(const char* text) { ccmap::bmtest::Line().text(text).end(); }

}  // extern "C"
