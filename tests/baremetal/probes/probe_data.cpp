// Negative control of the map-in-.bss promise: a static map next to one non-zero default member
// initialiser, the situation the check must catch (the whole object then moves to .data, and
// its initial image to flash; test link.map_in_bss).
#include "ccmap/map/stack.hpp"

struct MapWithTag {
  ccmap::Stack<ccmap::CadreConfig> map;
  int tag = 1;
};
// External linkage: the compiler may not fold an internal object that nothing writes away.
extern MapWithTag g_map;
MapWithTag g_map;

int main() { return g_map.map.initialised() || g_map.tag != 1 ? 1 : 0; }
