// The memory promise behind link.map_in_bss, on every target: a value-initialised
// Stack<CadreConfig> is all zero bytes (every default member initialiser is zero), which is
// what lets the compiler place a static map in .bss instead of an image of it in .data.
#include <cstdint>
#include <cstring>
#include <new>

#include "harness.hpp"
#include "shared_maps.hpp"

BM_CASE(memory, default_stack_is_all_zero_bytes) {
  ccmap::bmtest::CadreStack& storage = ccmap::bmtest::cadre_stack(1);
  storage.~Stack();  // trivial; the storage is reused below
  std::memset(static_cast<void*>(&storage), 0xA5, sizeof storage);
  auto* fresh = new (&storage) ccmap::bmtest::CadreStack();  // value-initialised, as a static object
  const auto* bytes = reinterpret_cast<const unsigned char*>(fresh);
  std::size_t first_non_zero = sizeof *fresh;
  for (std::size_t i = 0; i < sizeof *fresh; ++i) {
    if (bytes[i] != 0U) {
      first_non_zero = i;
      break;
    }
  }
  BM_CHECK_EQ(first_non_zero, sizeof *fresh,
              "offset of a non-zero byte in a default Stack<CadreConfig> (static maps then go to .data)");
  BM_CHECK(!fresh->initialised(), "a default-constructed stack claims to be initialised");
}
