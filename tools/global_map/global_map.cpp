// The global map's reader and assembler (global_map.hpp).
#include "global_map.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>

#include "ccmap/map/classify.hpp"
#include "ccmap/planner/footprint.hpp"

namespace ccmap::tools {
namespace {

template <typename Cell>
bool decode_cells(const std::uint8_t* data, std::size_t size, const PatchHeader& h, GlobalPatch* out) {
  constexpr std::size_t kCellBytes = detail::kPatchCellBytes<Cell>;
  const std::size_t count = static_cast<std::size_t>(h.tile_side) * static_cast<std::size_t>(h.tile_side);
  if (size != detail::patch_bytes(h.tile_side, kCellBytes)) {
    return false;
  }
  out->cells.assign(count, CcmCell{});
  for (std::size_t slot = 0; slot < count; ++slot) {
    detail::SnapshotReader r(data + detail::kPatchHeaderBytes + slot * kCellBytes, kCellBytes);
    Cell cell{};
    if (!detail::snapshot_read_cell(r, &cell)) {
      return false;
    }
    if (cell.weight > 0.0F && !detail::exchange_cell_valid(cell, h.cell_width_m)) {
      return false;
    }
    CcmCell& c = out->cells[slot];
    std::memcpy(&c, &cell, sizeof cell);  // the paper cell's nine floats are CcmCell's first nine
    if constexpr (!std::is_same_v<Cell, CcmCell>) {
      c.s_xy = 0.0F;
    }
  }
  return true;
}

/// Angle wrapped to (-pi, pi].
double wrap(double a) { return std::remainder(a, 2.0 * M_PI); }

}  // namespace

bool parse_global_patch(const std::uint8_t* data, std::size_t size, GlobalPatch* out) {
  PatchHeader h{};
  if (out == nullptr || !detail::patch_read_header(data, size, size, &h) || h.tile_side < 2 ||
      !(h.cell_width_m > 0.0F) || !std::isfinite(h.cell_width_m)) {
    return false;
  }
  out->header = h;
  if (h.cell_kind == detail::patch_cell_kind<CcmCell>()) {
    return decode_cells<CcmCell>(data, size, h, out);
  }
  if (h.cell_kind == detail::patch_cell_kind<CcmPaperCell>()) {
    return decode_cells<CcmPaperCell>(data, size, h, out);
  }
  return false;
}

bool read_patch_directory(const std::string& directory, int layer, std::vector<GlobalPatch>* patches,
                          PatchDirectoryCounts* counts, std::string* error) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::directory_iterator it(directory, ec);
  if (ec) {
    if (error != nullptr) *error = "cannot read the patch directory " + directory + ": " + ec.message();
    return false;
  }
  PatchDirectoryCounts c;
  std::vector<fs::path> files;
  const std::string prefix = "L" + std::to_string(layer) + "_";
  for (const fs::directory_entry& e : it) {
    const std::string name = e.path().filename().string();
    if (name.size() > prefix.size() + 4U && name.compare(0, prefix.size(), prefix) == 0 &&
        name.compare(name.size() - 4U, 4U, ".ccp") == 0) {
      files.push_back(e.path());
    }
  }
  std::sort(files.begin(), files.end());  // a deterministic order (the raster does not depend on it but for rounding)
  patches->clear();
  for (const fs::path& path : files) {
    ++c.files;
    std::ifstream in(path, std::ios::binary);
    const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    GlobalPatch p;
    PatchHeader h{};
    if (detail::patch_read_header(bytes.data(), bytes.size(), bytes.size(), &h) &&
        (h.cell_kind == detail::patch_cell_kind<KalmanCell>() || h.cell_kind == detail::patch_cell_kind<OmgCell>())) {
      ++c.unsupported;
      continue;
    }
    if (!in.bad() && parse_global_patch(bytes.data(), bytes.size(), &p) && p.header.key.layer == layer) {
      patches->push_back(std::move(p));
      ++c.used;
    } else {
      ++c.refused;
      c.refused_names.push_back(path.filename().string());
    }
  }
  if (counts != nullptr) *counts = c;
  return true;
}

bool assemble_global_map(const std::vector<GlobalPatch>& patches, const GlobalMapOptions& options,
                         GlobalRaster* raster, std::string* error) {
  const auto fail = [error](const std::string& message) {
    if (error != nullptr) *error = message;
    return false;
  };
  *raster = GlobalRaster{};
  if (patches.empty()) {
    return fail("no patches");
  }
  const float width_f = patches.front().header.cell_width_m;
  const double w = width_f;
  for (const GlobalPatch& p : patches) {
    if (!detail::same_float_bits(p.header.cell_width_m, width_f)) {
      return fail("patches of different cell widths (one layer a raster)");
    }
  }
  // The motion of each patch, and the extent of the moved cells.
  struct Motion {
    double c, s, tx, ty, turn;  // m' = R(turn) m + t
  };
  std::vector<Motion> motions;
  double x_lo = std::numeric_limits<double>::infinity(), y_lo = x_lo, x_hi = -x_lo, y_hi = -x_lo;
  for (const GlobalPatch& p : patches) {
    const PatchPose& W = p.header.pose;
    const PlanarPose C = options.apply_corrections ? p.header.corrected : PlanarPose{W.x_m, W.y_m, W.yaw_rad};
    const double turn = wrap(static_cast<double>(C.yaw_rad) - W.yaw_rad);
    const double c = std::cos(turn), s = std::sin(turn);
    const Motion m{c, s, C.x_m - (c * W.x_m - s * W.y_m), C.y_m - (s * W.x_m + c * W.y_m), turn};
    motions.push_back(m);
    const double t = p.header.tile_side;
    for (int corner = 0; corner < 4; ++corner) {
      const double x = (p.header.key.tile_x + (corner & 1)) * t * w, y = (p.header.key.tile_y + (corner >> 1)) * t * w;
      const double mx = m.c * x - m.s * y + m.tx, my = m.s * x + m.c * y + m.ty;
      x_lo = std::min(x_lo, mx), x_hi = std::max(x_hi, mx), y_lo = std::min(y_lo, my), y_hi = std::max(y_hi, my);
    }
  }
  GlobalRaster& r = *raster;
  r.cell_width_m = w;
  r.ix_min = static_cast<std::int64_t>(std::floor(x_lo / w)) - 1;
  r.iy_min = static_cast<std::int64_t>(std::floor(y_lo / w)) - 1;
  const std::int64_t nx = static_cast<std::int64_t>(std::floor(x_hi / w)) + 2 - r.ix_min;
  const std::int64_t ny = static_cast<std::int64_t>(std::floor(y_hi / w)) + 2 - r.iy_min;
  if (nx * ny > options.max_pixels) {
    return fail("the global map would have " + std::to_string(nx * ny) + " pixels, more than " +
                std::to_string(options.max_pixels));
  }
  r.nx = static_cast<int>(nx);
  r.ny = static_cast<int>(ny);
  const std::size_t n = static_cast<std::size_t>(nx * ny);
  std::vector<double> sum_w(n, 0.0), sum_h(n, 0.0), sum_v(n, 0.0), sum_gx(n, 0.0), sum_gy(n, 0.0);
  std::vector<int> rank(n, -1);
  std::vector<CellClass> worst(n, CellClass::kUnknown);
  const float threshold = options.normal_variance_threshold > 0.0F
                              ? options.normal_variance_threshold
                              : layer_threshold(options.params, -1, width_f);
  for (std::size_t k = 0; k < patches.size(); ++k) {
    const GlobalPatch& p = patches[k];
    const Motion& m = motions[k];
    const std::int32_t t = p.header.tile_side;
    for (std::int32_t j = 0; j < t; ++j) {
      for (std::int32_t i = 0; i < t; ++i) {
        const CcmCell& cell = p.cells[static_cast<std::size_t>(j * t + i)];
        if (!(cell.weight > 0.0F)) {
          continue;
        }
        ++r.cells_placed;
        const CcmSurface surface = ccm_surface(cell);
        const CellClass cls = classify_ccm(cell, surface, width_f, options.params, threshold);
        // The cell's centre and centroid, moved; its gradient turned with it.
        const double cx = (static_cast<double>(p.header.key.tile_x) * t + i + 0.5) * w;
        const double cy = (static_cast<double>(p.header.key.tile_y) * t + j + 0.5) * w;
        const double mx = cx + cell.mean_x, my = cy + cell.mean_y;
        const double ccx = m.c * cx - m.s * cy + m.tx, ccy = m.s * cx + m.c * cy + m.ty;
        const double px = m.c * mx - m.s * my + m.tx, py = m.s * mx + m.c * my + m.ty;
        const double gx = m.c * surface.slope_x - m.s * surface.slope_y;
        const double gy = m.s * surface.slope_x + m.c * surface.slope_y;
        // Pixels whose centres the moved footprint holds (at most 3 x 3 around its centre).
        const std::int64_t qx0 = static_cast<std::int64_t>(std::floor(ccx / w));
        const std::int64_t qy0 = static_cast<std::int64_t>(std::floor(ccy / w));
        for (std::int64_t qy = qy0 - 1; qy <= qy0 + 1; ++qy) {
          for (std::int64_t qx = qx0 - 1; qx <= qx0 + 1; ++qx) {
            const double ux = (qx + 0.5) * w - ccx, uy = (qy + 0.5) * w - ccy;
            const double a = m.c * ux + m.s * uy, b = -m.s * ux + m.c * uy;  // in the cell's frame
            if (!(a >= -0.5 * w && a < 0.5 * w && b >= -0.5 * w && b < 0.5 * w)) {
              continue;
            }
            const std::size_t at = static_cast<std::size_t>((qy - r.iy_min) * nx + (qx - r.ix_min));
            const double h = cell.mean_z + gx * ((qx + 0.5) * w - px) + gy * ((qy + 0.5) * w - py);
            sum_w[at] += cell.weight;
            sum_h[at] += cell.weight * h;
            sum_v[at] += cell.weight * static_cast<double>(surface.normal_variance);
            sum_gx[at] += cell.weight * gx;
            sum_gy[at] += cell.weight * gy;
            if (detail::hazard_rank(cls) > rank[at]) {
              rank[at] = detail::hazard_rank(cls);
              worst[at] = cls;
            }
          }
        }
      }
    }
  }
  const float nan = std::numeric_limits<float>::quiet_NaN();
  r.height.assign(n, nan);
  r.slope_x.assign(n, nan);
  r.slope_y.assign(n, nan);
  r.normal_var.assign(n, nan);
  r.weight.assign(n, nan);
  r.cell_class.assign(n, nan);
  for (std::size_t i = 0; i < n; ++i) {
    if (sum_w[i] > 0.0) {
      r.height[i] = static_cast<float>(sum_h[i] / sum_w[i]);
      r.slope_x[i] = static_cast<float>(sum_gx[i] / sum_w[i]);
      r.slope_y[i] = static_cast<float>(sum_gy[i] / sum_w[i]);
      r.normal_var[i] = static_cast<float>(sum_v[i] / sum_w[i]);
      r.weight[i] = static_cast<float>(sum_w[i]);
      r.cell_class[i] = static_cast<float>(worst[i]);
      r.hazard_pixels += is_lethal(worst[i]) ? 1 : 0;
    }
  }
  return true;
}

std::vector<LayerCellRow> global_map_rows(const GlobalRaster& raster, LayerWindow* extent) {
  std::vector<LayerCellRow> rows;
  const double w = raster.cell_width_m;
  for (int iy = 0; iy < raster.ny; ++iy) {
    for (int ix = 0; ix < raster.nx; ++ix) {
      const std::size_t i = static_cast<std::size_t>(iy) * static_cast<std::size_t>(raster.nx) + static_cast<std::size_t>(ix);
      if (!(raster.weight[i] > 0.0F)) {
        continue;
      }
      LayerCellRow r;
      r.ix = raster.ix_min + ix;
      r.iy = raster.iy_min + iy;
      r.cx = (static_cast<double>(r.ix) + 0.5) * w;
      r.cy = (static_cast<double>(r.iy) + 0.5) * w;
      r.res = w;
      r.weight = raster.weight[i];
      r.height = raster.height[i];
      r.slope_x = raster.slope_x[i];
      r.slope_y = raster.slope_y[i];
      r.normal_var = raster.normal_var[i];
      r.elev_var = raster.normal_var[i];
      r.cell_class = to_string(static_cast<CellClass>(static_cast<int>(raster.cell_class[i])));
      rows.push_back(r);
    }
  }
  if (extent != nullptr) {
    *extent = LayerWindow{raster.ix_min, raster.iy_min, raster.nx, raster.ny};
  }
  return rows;
}

}  // namespace ccmap::tools
