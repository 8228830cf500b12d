// Fits CCM cells to a synthetic inclined patch with one sub-cell rock and prints, per cell,
// height, inclination, normal variance and class: the smallest end-to-end use of the cell API.
#include <cmath>
#include <cstdio>
#include <random>

#include "ccmap/cell/ccm_cell.hpp"

int main() {
  constexpr int kCells = 6;
  constexpr float kWidth = 0.32F;           // 32 cm cells
  constexpr float kSlope = 0.18F;           // ~10 deg along x
  constexpr float kRockHeight = 0.24F;      // 24 cm rock, 0.2 m across (smaller than a cell)
  constexpr float kRockX = 0.90F, kRockY = 0.85F, kRockRadius = 0.10F;
  constexpr float kNoise = 0.005F;
  // Threshold: normal variance of a 24 cm step at 50 % coverage, h^2/16 (docs/design.md).
  const float threshold = kRockHeight * kRockHeight / 16.0F * 0.5F;
  const float max_slope = std::tan(20.0F * 3.14159265F / 180.0F);

  ccmap::CcmCell cells[kCells][kCells] = {};
  std::mt19937 rng(42);
  std::uniform_real_distribution<float> u(0.0F, kCells * kWidth);
  std::normal_distribution<float> n(0.0F, kNoise);
  for (int i = 0; i < 200000; ++i) {
    const float x = u(rng), y = u(rng);
    float z = kSlope * x + n(rng);
    if (std::hypot(x - kRockX, y - kRockY) < kRockRadius) z += kRockHeight;
    const int ix = static_cast<int>(x / kWidth), iy = static_cast<int>(y / kWidth);
    if (ix < 0 || iy < 0 || ix >= kCells || iy >= kCells) continue;
    const float cx = (static_cast<float>(ix) + 0.5F) * kWidth, cy = (static_cast<float>(iy) + 0.5F) * kWidth;
    if (ccmap::ccm_update(cells[iy][ix], x - cx, y - cy, z, 1.0F, 1000.0F) != ccmap::Status::kOk) return 1;
  }
  std::printf("CCM cells of %.0f cm on a %.1f deg slope with a %.0f cm rock at (%.2f, %.2f)\n",
              kWidth * 100.0F, std::atan(kSlope) * 180.0F / 3.14159265F, kRockHeight * 100.0F, kRockX, kRockY);
  std::printf("%4s %4s %8s %8s %8s %12s  %s\n", "ix", "iy", "height", "slope_x", "slope_y", "normal_var", "class");
  int obstacles = 0;
  for (int iy = 0; iy < kCells; ++iy) {
    for (int ix = 0; ix < kCells; ++ix) {
      const ccmap::CcmCell& c = cells[iy][ix];
      const ccmap::CcmSurface s = ccmap::ccm_surface(c);
      const char* cls = "traversable";
      if (!ccmap::ccm_is_covered(c, kWidth, 0.8F, 3.0F)) cls = "unknown";
      else if (s.normal_variance > threshold) { cls = "obstacle"; ++obstacles; }
      else if (ccmap::ccm_inclination(s) > max_slope) cls = "steep";
      std::printf("%4d %4d %8.3f %8.3f %8.3f %12.3e  %s\n", ix, iy, ccmap::ccm_height_at(c, s, 0.0F, 0.0F),
                  s.slope_x, s.slope_y, s.normal_variance, cls);
    }
  }
  std::printf("%d obstacle cell(s) found (the rock covers parts of cells (2,2) and (3,2))\n", obstacles);
  return obstacles > 0 ? 0 : 2;
}
