# cmake -DPYTHON=... -DCHECKER=tools/check-paths -DDIR=... -P check_paths_check.cmake
# Builds a fixture repository in DIR with known stale references, runs the checker on it and
# compares its findings with the planted ones; then fixes them and expects a clean pass.
file(REMOVE_RECURSE "${DIR}")
file(MAKE_DIRECTORY "${DIR}/include/ccmap/map" "${DIR}/src/map" "${DIR}/tests/map" "${DIR}/tools/sim" "${DIR}/docs")
file(WRITE "${DIR}/include/ccmap/map/frame_chunk.hpp" "// exists\n")
file(WRITE "${DIR}/tools/sim/hazard.hpp" "// exists\n")
file(WRITE "${DIR}/tests/map/CMakeLists.txt" "# exists\n")
file(WRITE "${DIR}/src/map/a.cpp"
  "// Good: map/frame_chunk.hpp, include/ccmap/map/frame_chunk.hpp, ccmap/map/frame_chunk.hpp,\n"
  "// sim/hazard.hpp, tests/map/ (a folder), tests/<area>/CMakeLists.txt (a template),\n"
  "// https://example.org/tools/nothing, build/host-release/tools/x, 1/w and m/s are no paths.\n"
  "const char* s = \"tests/not_a_comment.cpp\";  // a literal is not a comment\n"
  "/* Stale: tests/map/x_test.cpp and\n"
  "   map/gone.hpp, */\n"
  "int f();  // stale: tools/gone\n")
file(WRITE "${DIR}/docs/notes.md" "See `include/ccmap/map/nothere.hpp` and [the map](../include/ccmap/map/frame_chunk.hpp).\n")
file(WRITE "${DIR}/CMakeLists.txt" "add_subdirectory(src) # see tests/tools/io.cmake\n")
file(WRITE "${DIR}/README.md" "Read docs/notes.md.\n")
file(WRITE "${DIR}/tests/CMakeLists.txt" "include(\${CMAKE_CURRENT_LIST_DIR}/x.cmake OPTIONAL)\n")
include(${CMAKE_CURRENT_LIST_DIR}/checker_fixture.cmake)
ccmap_check_fixture(1 6
  "CMakeLists.txt:1: 'tests/tools/io.cmake'"
  "docs/notes.md:1: 'include/ccmap/map/nothere.hpp'"
  "src/map/a.cpp:5: 'tests/map/x_test.cpp'"
  "src/map/a.cpp:6: 'map/gone.hpp'"
  "src/map/a.cpp:7: 'tools/gone'"
  "tests/CMakeLists.txt:1: conditional pickup")

# Fixed: the same tree with the stale references gone passes.
file(WRITE "${DIR}/src/map/a.cpp" "// Good: map/frame_chunk.hpp\nint f();\n")
file(WRITE "${DIR}/docs/notes.md" "See `include/ccmap/map/frame_chunk.hpp`.\n")
file(WRITE "${DIR}/CMakeLists.txt" "add_subdirectory(src) # see tests/map/CMakeLists.txt\n")
file(WRITE "${DIR}/tests/CMakeLists.txt" "add_subdirectory(map)\n")
ccmap_check_fixture(0 0)
file(REMOVE_RECURSE "${DIR}")
