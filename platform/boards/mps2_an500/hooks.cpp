// The integrator's three hooks of platform/baremetal (ccmap_bm_monotonic_ns, ccmap_bm_log_write,
// ccmap_bm_fault) for the mps2-an500 board: the clock from timer 0, log and fault reports as
// semihosting text lines. Each returns in bounded time and allocates nothing; they assume one
// calling context (no interrupt handler updates the map), as the core's contract allows.
#include <cstddef>
#include <cstdint>

#include "board.h"

namespace {

std::uint32_t g_fault_count = 0U;
std::uint32_t g_log_count = 0U;

// Extends the 32-bit tick counter to 64 bits; correct if called at least once per wrap (171 s).
std::uint32_t g_last_ticks = 0U;
std::uint64_t g_wrapped_ticks = 0U;

/// Appends text to out[*n..capacity-1), NUL-terminated, truncating.
void append(char* out, std::size_t capacity, std::size_t* n, const char* text) noexcept {
  if (text == nullptr) {
    text = "?";
  }
  while (*text != '\0' && *n + 1U < capacity) {
    out[(*n)++] = *text++;
  }
  out[*n] = '\0';
}

void append_int(char* out, std::size_t capacity, std::size_t* n, int value) noexcept {
  char digits[12];
  std::size_t count = 0U;
  std::uint32_t magnitude = value < 0 ? 0U - static_cast<std::uint32_t>(value) : static_cast<std::uint32_t>(value);
  do {
    digits[count++] = static_cast<char>('0' + magnitude % 10U);
    magnitude /= 10U;
  } while (magnitude != 0U);
  if (value < 0) {
    digits[count++] = '-';
  }
  char text[12];
  for (std::size_t i = 0; i < count; ++i) {
    text[i] = digits[count - 1U - i];
  }
  text[count] = '\0';
  append(out, capacity, n, text);
}

}  // namespace

extern "C" {

std::uint64_t ccmap_bm_monotonic_ns(void) {
  const std::uint32_t now = ccmap_board_ticks();
  if (now < g_last_ticks) {
    g_wrapped_ticks += std::uint64_t{1} << 32U;
  }
  g_last_ticks = now;
  return (g_wrapped_ticks + now) * (1000000000U / CCMAP_BOARD_TIMER_HZ);
}

void ccmap_bm_log_write(int level, const char* message) {
  if (g_log_count != UINT32_MAX) {
    ++g_log_count;
  }
  if (message == nullptr) {
    return;
  }
  static const char* const kNames[] = {"debug", "info", "warning", "error"};
  char line[160];
  std::size_t n = 0U;
  append(line, sizeof line, &n, "ccmap[");
  append(line, sizeof line, &n, level >= 0 && level < 4 ? kNames[level] : "?");
  append(line, sizeof line, &n, "] ");
  append(line, sizeof line, &n, message);
  append(line, sizeof line, &n, "\n");
  ccmap_board_write(line);
}

void ccmap_bm_fault(const char* file, int line_number, const char* expression) {
  if (g_fault_count != UINT32_MAX) {
    ++g_fault_count;
  }
  char line[200];
  std::size_t n = 0U;
  append(line, sizeof line, &n, "ccmap[fault] ");
  append(line, sizeof line, &n, file);
  append(line, sizeof line, &n, ":");
  append_int(line, sizeof line, &n, line_number);
  append(line, sizeof line, &n, ": ");
  append(line, sizeof line, &n, expression);
  append(line, sizeof line, &n, "\n");
  ccmap_board_write(line);
}

std::uint32_t ccmap_board_fault_count(void) { return g_fault_count; }
std::uint32_t ccmap_board_log_count(void) { return g_log_count; }

}  // extern "C"
