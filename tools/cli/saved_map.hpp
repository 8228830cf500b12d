// Maps saved by the ccmap tool (ccmap map --save FILE, read by ccmap merge): the library's
// snapshot (include/ccmap/persistence/snapshot.hpp, unchanged) followed by a record of the absolute
// origin the tool subtracted in double before the float library saw the points, so that maps
// made from different files align without an offset and merged output is absolute again.
//
//   [snapshot: snapshot_size<Config>() bytes]
//   [origin record, 48 bytes, little-endian]
//      8  magic "CCMORIG1"
//      8  coarsest cell width w_c (IEEE-754 binary64 bits, m)
//     24  origin in whole coarsest cells: x, y, z (int64 each; origin = cells * w_c)
//      4  reserved 0
//      4  CRC-32 (zlib) of the 44 bytes before it
// A file of exactly the snapshot's size (a snapshot written by flight software) has no record:
// its origin is 0. Host tool code: reads whole files, refuses with a message, never guesses.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace ccmap::tools {

inline constexpr std::size_t kOriginRecordBytes = 48;

struct SavedMap {
  std::vector<std::uint8_t> snapshot;
  bool has_origin = false;
  double coarsest_width_m = 0.0;
  std::int64_t origin_cells[3] = {0, 0, 0};  ///< origin / coarsest width, per axis
};

/// Writes map.snapshot and, when has_origin, the origin record. False with a reason.
bool write_saved_map(const std::string& path, const SavedMap& map, std::string* error);

/// Reads a saved map whose snapshot part has `snapshot_size` bytes (the preset's). False with a
/// reason for a file of another size, or an origin record with a bad magic, reserved field, CRC
/// or width. The snapshot itself is checked by the library when it is used.
bool read_saved_map(const std::string& path, std::size_t snapshot_size, SavedMap* map, std::string* error);

}  // namespace ccmap::tools
