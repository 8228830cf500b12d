// Host point-cloud readers for the tools: PLY (ASCII, binary little/big endian), LAS 1.0-1.4
// (uncompressed, point formats 0-10; x, y, z only) and plain text (`x y z [w]` per line).
//
// Coordinates are returned in double, exactly as stored (absolute world coordinates such as
// UTM are fine): converting to the library's float frame is the caller's job, after it has
// subtracted a local origin.
//
// Robustness contract (these readers are fuzzed): every size taken from a header is checked
// against the bytes actually present before it is used; allocations are capped by the input
// size; a truncated or malformed file gives `ok() == false` with a one-line message, never a
// read past the buffer and never a partial cloud presented as complete. Points with a NaN/Inf
// coordinate are not an error: they are skipped and counted in `skipped_non_finite`.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace ccmap::tools {

enum class CloudFormat : std::uint8_t { kAuto, kPly, kLas, kText };

/// One point cloud in world coordinates (metres, double).
struct Cloud {
  std::vector<double> x, y, z;  ///< finite points only, same length
  std::vector<double> w;        ///< per-point weight (same length as x) if has_weight, else empty
  bool has_weight = false;      ///< the file carried a weight column/property
  std::uint64_t declared = 0;   ///< points the file declares (PLY/LAS header) or lines with a point (text)
  std::uint64_t skipped_non_finite = 0;  ///< points dropped because x, y or z is NaN/Inf
  std::string format;           ///< human-readable description, e.g. "LAS 1.2 format 1"
  std::string error;            ///< empty on success, else a one-line reason (no "ccmap:" prefix)

  [[nodiscard]] bool ok() const { return error.empty(); }
  [[nodiscard]] std::size_t size() const { return x.size(); }
};

/// Largest file the readers accept (bytes); larger files give an error instead of a huge read.
inline constexpr std::uint64_t kMaxCloudFileBytes = 8ULL << 30;  // 8 GiB

/// Reads a cloud from a file. kAuto picks the format from the magic bytes ("ply", "LASF"),
/// then from the extension (.ply, .las; .laz is refused as compressed; anything else is text).
/// A .ply/.las extension without the matching magic is an error.
[[nodiscard]] Cloud read_cloud(const std::string& path, CloudFormat format = CloudFormat::kAuto);

/// The same parsers on a memory buffer (the fuzzing entry points). `name` is only used for
/// the extension when format is kAuto.
[[nodiscard]] Cloud read_cloud_buffer(const std::uint8_t* data, std::size_t size, const std::string& name,
                                      CloudFormat format = CloudFormat::kAuto);
[[nodiscard]] Cloud read_ply(const std::uint8_t* data, std::size_t size);
[[nodiscard]] Cloud read_las(const std::uint8_t* data, std::size_t size);
[[nodiscard]] Cloud read_text(const std::uint8_t* data, std::size_t size);

/// Robot poses for a sequence of frames: one line `x y z yaw` per frame (metres, radians, map
/// frame), `#` comments and blank lines allowed. Returns false with a one-line message on a
/// malformed line, a non-finite value or a missing file.
struct Pose {
  double x = 0.0, y = 0.0, z = 0.0, yaw = 0.0;
};
[[nodiscard]] bool read_poses(const std::string& path, std::vector<Pose>* poses, std::string* error);

}  // namespace ccmap::tools
