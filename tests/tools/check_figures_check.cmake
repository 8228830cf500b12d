# cmake -DPYTHON=... -DCHECKER=tools/check-figures -DDIR=... -P check_figures_check.cmake
# Builds a fixture repository in DIR whose texts state figures against its docs/figures.md and
# name sections, runs the checker and compares its findings with the planted ones (each a
# contradiction, a missing section, a missing key); then fixes them and expects a clean pass.
file(REMOVE_RECURSE "${DIR}")
file(MAKE_DIRECTORY "${DIR}/docs" "${DIR}/include/ccmap/map" "${DIR}/src")
file(WRITE "${DIR}/docs/figures.md"
  "# figures\n\n| key | value | unit | what | source |\n|---|---|---|---|---|\n"
  "| `front.chunk_points` | 256 | points | x | y |\n"
  "| `free_space.u_fraction_bits` | 8 | bits | x | y |\n"
  "| `front.chunk_overrun_us` | 8.4 | us | x | y |\n")
file(WRITE "${DIR}/docs/design.md" "# Design\n\n## 1. One\n\n### 1.1 One point one\n\n## 8. Map exchange\n")
file(WRITE "${DIR}/README.md"
  "The front takes 128-point chunks (stale) and chunks of 256 points (right).\n"
  "Map exchange: [docs/design.md](docs/design.md)\nsection 6 (gone), docs/design.md section 8 (right),\n"
  "docs/design.md section 1.1 (right), docs/nothere.md section 2 (no such doc).\n"
  "The overrun of a time budget is at most one chunk (256 points, ~20 us at the clock).\n"
  "The overrun is at most one chunk (256 points, ~9 us): within 10 %.\n"
  "Row [figures](docs/figures.md) `front.chunk_points` exists, [figures](docs/figures.md) `no.such_key` does not.\n"
  "A list: [design](docs/design.md) sections 1, 8 and 7 (7 is missing).\n")
file(WRITE "${DIR}/include/ccmap/map/a.hpp"
  "// The fields a stage reads (routing code, Q18 position,\n"
  "// squared range): one line too many.\n"
  "int a();  // chunks of\n"
  "          // 512 points: a claim across comment lines\n")
include(${CMAKE_CURRENT_LIST_DIR}/checker_fixture.cmake)
ccmap_check_fixture(1 8
  "README.md:1: '128-point chunks' contradicts docs/figures.md `front.chunk_points` = 256"
  "README.md:2: 'docs/design.md"
  "section 6': docs/design.md has no section 6"
  "README.md:4: 'docs/nothere.md section 2': docs/nothere.md does not exist"
  "README.md:5: 'overrun of a time budget is at most one chunk (256 points, ~20 us' contradicts"
  "README.md:7: links docs/figures.md `no.such_key`"
  "README.md:8: 'docs/design.md) sections 1, 8 and 7': docs/design.md has no section 7"
  "include/ccmap/map/a.hpp:1: 'Q18 position' contradicts docs/figures.md `free_space.u_fraction_bits` = 8"
  "include/ccmap/map/a.hpp:3: 'chunks of 512 points' contradicts")

# Fixed: the same tree with the claims made true passes.
file(WRITE "${DIR}/README.md"
  "The front takes 256-point chunks. Map exchange: docs/design.md section 8; docs/design.md section 1.1.\n"
  "The overrun of a time budget is at most one chunk (256 points, ~8 us at the clock).\n"
  "Row [figures](docs/figures.md) `front.chunk_points`.\n")
file(WRITE "${DIR}/include/ccmap/map/a.hpp" "// The fields a stage reads (routing code, position).\nint a();\n")
ccmap_check_fixture(0 0)
file(REMOVE_RECURSE "${DIR}")
