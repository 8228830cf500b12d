#include "saved_map.hpp"

#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>

#include "ccmap/persistence/snapshot.hpp"

namespace ccmap::tools {
namespace {

constexpr char kMagic[8] = {'C', 'C', 'M', 'O', 'R', 'I', 'G', '1'};

void put_u64(std::vector<std::uint8_t>& out, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}
std::uint64_t get_u64(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= static_cast<std::uint64_t>(p[i]) << (8 * i);
  return v;
}
std::uint32_t get_u32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | static_cast<std::uint32_t>(p[1]) << 8 |
         static_cast<std::uint32_t>(p[2]) << 16 | static_cast<std::uint32_t>(p[3]) << 24;
}

}  // namespace

bool write_saved_map(const std::string& path, const SavedMap& map, std::string* error) {
  std::vector<std::uint8_t> bytes = map.snapshot;
  if (map.has_origin) {
    const std::size_t begin = bytes.size();
    bytes.insert(bytes.end(), kMagic, kMagic + 8);
    std::uint64_t width_bits = 0;
    std::memcpy(&width_bits, &map.coarsest_width_m, sizeof width_bits);
    put_u64(bytes, width_bits);
    for (const std::int64_t c : map.origin_cells) put_u64(bytes, static_cast<std::uint64_t>(c));
    bytes.insert(bytes.end(), 4, 0U);
    const std::uint32_t crc = crc32_update(0U, bytes.data() + begin, bytes.size() - begin);
    for (int i = 0; i < 4; ++i) bytes.push_back(static_cast<std::uint8_t>(crc >> (8 * i)));
  }
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  out.close();
  if (!out) {
    *error = "cannot write '" + path + "'";
    return false;
  }
  return true;
}

bool read_saved_map(const std::string& path, std::size_t snapshot_size, SavedMap* map, std::string* error) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    *error = "cannot open '" + path + "'";
    return false;
  }
  std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  SavedMap m;
  if (bytes.size() == snapshot_size) {
    m.snapshot = std::move(bytes);
    *map = std::move(m);
    return true;
  }
  if (bytes.size() != snapshot_size + kOriginRecordBytes) {
    *error = path + ": " + std::to_string(bytes.size()) + " bytes, expected a snapshot of this preset (" +
             std::to_string(snapshot_size) + " bytes, or " + std::to_string(snapshot_size + kOriginRecordBytes) +
             " with its origin)";
    return false;
  }
  const std::uint8_t* r = bytes.data() + snapshot_size;
  const std::uint32_t crc = crc32_update(0U, r, kOriginRecordBytes - 4);
  if (std::memcmp(r, kMagic, 8) != 0 || get_u32(r + 40) != 0U || get_u32(r + 44) != crc) {
    *error = path + ": the origin record after the snapshot is corrupt";
    return false;
  }
  const std::uint64_t width_bits = get_u64(r + 8);
  std::memcpy(&m.coarsest_width_m, &width_bits, sizeof width_bits);
  if (!std::isfinite(m.coarsest_width_m) || !(m.coarsest_width_m > 0.0)) {
    *error = path + ": the origin record holds no valid cell width";
    return false;
  }
  for (int a = 0; a < 3; ++a) m.origin_cells[a] = static_cast<std::int64_t>(get_u64(r + 16 + 8 * a));
  m.has_origin = true;
  bytes.resize(snapshot_size);
  m.snapshot = std::move(bytes);
  *map = std::move(m);
  return true;
}

}  // namespace ccmap::tools
