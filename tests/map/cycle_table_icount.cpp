// The flight cycle of cycle_icount.cpp (regions 1-5 as there) on Stack<WithEveryLineOfSight<
// CadreConfig>>, free space from the viewshed table fed by one point in K (free_space_rays =
// detail::free_space_table_rays(K); docs/performance.md 13). Not a budget test: the table is not
// the presets' free space.
//
//   ccmap_cycle_table_icount [cycles [K]]   default 3 cycles, K = 8 (1, 2, 4, 8 or 16)
#define CCMAP_CYCLE_TABLE 1
#include "cycle_icount.cpp"  // NOLINT(bugprone-suspicious-include): the same cycle, another stack

#include "ccmap/map/visibility/sight_table.hpp"

int main(int argc, char** argv) {
  const int cycles = argc > 1 ? std::atoi(argv[1]) : 3;
  table_stride = argc > 2 ? std::atoi(argv[2]) : 8;
  if (cycles < 1 || cycles > 100 || argc > 3 ||
      ccmap::detail::sight_stride_of_rays(ccmap::detail::free_space_table_rays(table_stride)) != table_stride) {
    std::fprintf(stderr, "usage: ccmap_cycle_table_icount [cycles 1..100 [1|2|4|8|16]]\n");
    return 2;
  }
  return run<ccmap::WithEveryLineOfSight<ccmap::CadreConfig>>(cycles);
}
