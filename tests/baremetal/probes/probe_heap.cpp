// Negative control of the no-heap promise: a program that allocates. Its link with the board's
// linker script must fail (check_link_fails.cmake; test link.no_heap).
#include <cstdlib>
#include <new>

int main() {
  void* block = std::malloc(64);
  int* value = new int(3);
  const int ok = block != nullptr && *value == 3 ? 0 : 1;
  std::free(block);
  delete value;
  return ok;
}
