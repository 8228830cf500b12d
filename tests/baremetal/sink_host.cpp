// Host (and aarch64 Linux) side of the portable harness: output to stdout, the filter from argv.
#include <cstdio>
#include <cstring>

#include "harness.hpp"

extern "C" void ccmap_test_write(const char* text) {
  (void)std::fputs(text, stdout);
  (void)std::fflush(stdout);
}

int main(int argc, char** argv) {
  char filter[256] = {};
  std::size_t n = 0U;
  for (int i = 1; i < argc; ++i) {
    const std::size_t length = std::strlen(argv[i]);
    if (n + length + 2U > sizeof filter) {
      std::fprintf(stderr, "filter too long\n");
      return 2;
    }
    std::memcpy(filter + n, argv[i], length);
    n += length;
    filter[n++] = ' ';
  }
  filter[n] = '\0';
  return ccmap::bmtest::run(filter);
}
