// Real terrain of ../shared/data (its README) for tests and benchmarks: the HiRISE Mars DTM
// (ESRI ASCII grid) as a scaled height field, the 10 x 10 m Lone Star crop (text x y z) as
// points. Each loader answers false when the file is absent: callers skip with a message.
#pragma once

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

namespace ccmap::test {

/// The data directory: $CCMAP_DATA_DIR, else `fallback` (a build's ../shared/data).
inline std::string terrain_data_dir(const char* fallback) {
  const char* env = std::getenv("CCMAP_DATA_DIR");
  return env != nullptr && env[0] != '\0' ? std::string(env) : std::string(fallback);
}

/// The Mars DTM, heights about their mean, x, y and z scaled by `scale`; (0, 0) its south-west
/// corner, x east, y north (m after scaling).
struct Dtm {
  int cols = 0;
  int rows = 0;
  float cell = 0.0F;
  std::vector<float> z;  ///< rows from the north, as in the file
  [[nodiscard]] float width() const { return cell * static_cast<float>(cols - 1); }
  [[nodiscard]] float height() const { return cell * static_cast<float>(rows - 1); }
  /// Bilinear height, clamped to the grid.
  [[nodiscard]] float at(float x, float y) const {
    const float u = std::fmin(std::fmax(x / cell, 0.0F), static_cast<float>(cols - 1) - 0.001F);
    const float v = std::fmin(std::fmax(y / cell, 0.0F), static_cast<float>(rows - 1) - 0.001F);
    const int i = static_cast<int>(u);
    const int j = static_cast<int>(v);
    const float a = u - static_cast<float>(i);
    const float b = v - static_cast<float>(j);
    auto h = [&](int ii, int jj) { return z[static_cast<std::size_t>((rows - 1 - jj) * cols + ii)]; };
    return (1 - a) * (1 - b) * h(i, j) + a * (1 - b) * h(i + 1, j) + (1 - a) * b * h(i, j + 1) +
           a * b * h(i + 1, j + 1);
  }
};

inline std::string mars_dtm_file(const std::string& dir) { return dir + "/hirise_mars_dtm/mars_dtm_1.01m.asc"; }
inline std::string lone_star_crop_file(const std::string& dir) {
  return dir + "/lone_star_tls/lone_star_crop_10x10m_x515386.6_y4918368.4.xyz";
}

inline bool load_dtm(const std::string& path, float scale, Dtm* out) {
  std::ifstream in(path);
  if (!in.good()) {
    return false;
  }
  std::string key;
  double value = 0.0;
  for (int k = 0; k < 6; ++k) {
    in >> key >> value;
    if (key == "ncols") out->cols = static_cast<int>(value);
    if (key == "nrows") out->rows = static_cast<int>(value);
    if (key == "cellsize") out->cell = static_cast<float>(value) * scale;
  }
  if (out->cols < 2 || out->rows < 2) {
    return false;
  }
  double sum = 0.0;
  std::vector<double> raw(static_cast<std::size_t>(out->cols) * static_cast<std::size_t>(out->rows));
  for (double& v : raw) {
    in >> v;
    sum += v;
  }
  if (!in) {
    return false;
  }
  const double mean = sum / static_cast<double>(raw.size());
  out->z.clear();
  for (const double v : raw) {
    out->z.push_back(static_cast<float>((v - mean) * scale));
  }
  return true;
}

/// Points of a text x y z file, less their centroid (double: UTM coordinates); false if absent.
inline bool load_xyz_centred(const std::string& path, std::vector<double>* xyz) {
  std::ifstream in(path);
  if (!in.good()) {
    return false;
  }
  double x = 0.0, y = 0.0, z = 0.0;
  double sx = 0.0, sy = 0.0, sz = 0.0;
  xyz->clear();
  while (in >> x >> y >> z) {
    xyz->insert(xyz->end(), {x, y, z});
    sx += x;
    sy += y;
    sz += z;
  }
  const double n = static_cast<double>(xyz->size() / 3U);
  if (n < 1.0) {
    return false;
  }
  for (std::size_t i = 0; i < xyz->size(); i += 3U) {
    (*xyz)[i] -= sx / n;
    (*xyz)[i + 1U] -= sy / n;
    (*xyz)[i + 2U] -= sz / n;
  }
  return true;
}

}  // namespace ccmap::test
