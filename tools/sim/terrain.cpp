#include "sim/terrain.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "sim/rng.hpp"

namespace ccmap::sim {

namespace {

double quintic(double t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); }

double lattice_value(std::int64_t ix, std::int64_t iy, std::uint64_t seed) {
  const std::uint64_t h = hash_combine(seed, static_cast<std::uint64_t>(ix), static_cast<std::uint64_t>(iy));
  return static_cast<double>(h >> 11) * (2.0 / 9007199254740992.0) - 1.0;
}

constexpr double kCraterOuter = 2.5;  // rim falloff reaches 0 at 2.5 R

double crater_profile(const Crater& c, double x, double y) {
  const double radius = 0.5 * c.diameter_m;
  const double dx = x - c.x, dy = y - c.y;
  const double d2 = dx * dx + dy * dy;
  const double outer = kCraterOuter * radius;
  if (d2 >= outer * outer || radius <= 0.0) return 0.0;
  const double r = std::sqrt(d2) / radius;
  if (r < 1.0) return -c.depth_m + (c.depth_m + c.rim_m) * r * r;
  const double tail = 1.0 / (kCraterOuter * kCraterOuter * kCraterOuter);
  return c.rim_m * (1.0 / (r * r * r) - tail) / (1.0 - tail);
}

}  // namespace

double value_noise(double x, double y, std::uint64_t seed) {
  const double fx = std::floor(x), fy = std::floor(y);
  const auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy);
  const double tx = quintic(x - fx), ty = quintic(y - fy);
  const double v00 = lattice_value(ix, iy, seed), v10 = lattice_value(ix + 1, iy, seed);
  const double v01 = lattice_value(ix, iy + 1, seed), v11 = lattice_value(ix + 1, iy + 1, seed);
  const double a = v00 + (v10 - v00) * tx;
  const double b = v01 + (v11 - v01) * tx;
  return a + (b - a) * ty;
}

// Gentle lunar-like ground: 3 % / 2 % regional slope, +-~10 cm rolling over 10-30 m, 2 cm
// fractal roughness down to ~6 cm wavelengths, 0.3 rocks/m^2 of 8 cm to 80 cm (D^-2.5, height
// = D/2: about one rock of >= 40 cm per 60 m^2), one 1-5 m crater per 150 m^2.
TerrainParams lunar_terrain_params(const Rect& area, std::uint64_t seed) {
  TerrainParams p;
  p.area = area;
  p.seed = seed;
  p.slope_x = 0.03;
  p.slope_y = -0.02;
  p.rolling = RollingParams{3, 0.15, 10.0, 30.0};
  p.roughness = RoughnessParams{4, 0.02, 1.0, 0.5};
  p.rocks = RockParams{0.3, 0.08, 0.8, 2.5, 0.5};
  p.craters = CraterParams{static_cast<int>(std::lround(area.area() / 150.0)), 1.0, 5.0, 0.12, 0.02};
  return p;
}

ProceduralTerrain::ProceduralTerrain() { rebuild_rock_index(); }

ProceduralTerrain::ProceduralTerrain(const TerrainParams& params) : params_(params) {
  // Independent streams per feature class, so changing one class keeps the others.
  Rng wave_rng(hash_combine(params.seed, 1));
  for (int i = 0; i < params.rolling.waves; ++i) {
    const double dir = wave_rng.uniform(0.0, 2.0 * kPi);
    const double wavelength = wave_rng.uniform(params.rolling.min_wavelength_m, params.rolling.max_wavelength_m);
    const double k = 2.0 * kPi / wavelength;
    const double amplitude = params.rolling.amplitude_m / std::sqrt(static_cast<double>(params.rolling.waves)) *
                             wave_rng.uniform(0.5, 1.0);
    waves_.push_back(Wave{k * std::cos(dir), k * std::sin(dir), wave_rng.uniform(0.0, 2.0 * kPi), amplitude});
  }
  const Rect& a = params.area;
  Rng rock_rng(hash_combine(params.seed, 2));
  const RockParams& rp = params.rocks;
  const auto rock_count = static_cast<long>(std::lround(rp.density_per_m2 * a.area()));
  const double ratio = std::pow(rp.min_diameter_m / rp.max_diameter_m, rp.exponent);
  for (long i = 0; i < rock_count; ++i) {
    // Inverse CDF of the truncated Pareto law P(D >= d) ~ d^-exponent on [min, max].
    const double u = rock_rng.uniform();
    const double d = rp.min_diameter_m * std::pow(1.0 - u * (1.0 - ratio), -1.0 / rp.exponent);
    Rock r;
    r.x = rock_rng.uniform(a.x0, a.x1);
    r.y = rock_rng.uniform(a.y0, a.y1);
    r.diameter_m = d;
    r.height_m = rp.height_ratio * d;
    rocks_.push_back(r);
  }
  Rng crater_rng(hash_combine(params.seed, 3));
  const CraterParams& cp = params.craters;
  for (int i = 0; i < cp.count; ++i) {
    Crater c;
    c.x = crater_rng.uniform(a.x0, a.x1);
    c.y = crater_rng.uniform(a.y0, a.y1);
    c.diameter_m = cp.min_diameter_m * std::pow(cp.max_diameter_m / cp.min_diameter_m, crater_rng.uniform());
    c.depth_m = cp.depth_ratio * c.diameter_m;
    c.rim_m = cp.rim_ratio * c.diameter_m;
    craters_.push_back(c);
  }
  rebuild_rock_index();
}

void ProceduralTerrain::add_rock(const Rock& rock) {
  rocks_.push_back(rock);
  rebuild_rock_index();
}

void ProceduralTerrain::add_box(const Box& box) { boxes_.push_back(box); }

void ProceduralTerrain::add_crater(const Crater& crater) { craters_.push_back(crater); }

void ProceduralTerrain::add_ditch(const Ditch& ditch) { ditches_.push_back(ditch); }

double ProceduralTerrain::negative_depth(double x, double y) const {
  double depth = 0.0;
  for (const Crater& c : craters_) depth -= std::min(0.0, crater_profile(c, x, y));
  for (const Ditch& d : ditches_) {
    if (x >= d.x0 && x <= d.x1 && y >= d.y0 && y <= d.y1) depth += d.depth_m;
  }
  return depth;
}

void ProceduralTerrain::rebuild_rock_index() {
  bin_start_.clear();
  bin_items_.clear();
  bins_x_ = bins_y_ = 0;
  if (rocks_.empty()) return;
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300, dmax = 0.0;
  for (const Rock& r : rocks_) {
    const double rad = 0.5 * r.diameter_m;
    x0 = std::min(x0, r.x - rad);
    y0 = std::min(y0, r.y - rad);
    x1 = std::max(x1, r.x + rad);
    y1 = std::max(y1, r.y + rad);
    dmax = std::max(dmax, r.diameter_m);
  }
  // Bins of ~the largest diameter, at most ~1e6 of them.
  bin_size_ = std::max({dmax, 1e-3, std::sqrt((x1 - x0) * (y1 - y0) / 1.0e6)});
  bin_x0_ = x0;
  bin_y0_ = y0;
  bins_x_ = static_cast<int>((x1 - x0) / bin_size_) + 1;
  bins_y_ = static_cast<int>((y1 - y0) / bin_size_) + 1;
  const std::size_t nbins = static_cast<std::size_t>(bins_x_) * static_cast<std::size_t>(bins_y_);
  std::vector<int> counts(nbins + 1, 0);
  auto for_each_bin = [&](const Rock& r, auto&& fn) {
    const double rad = 0.5 * r.diameter_m;
    const int i0 = std::max(0, static_cast<int>((r.x - rad - bin_x0_) / bin_size_));
    const int i1 = std::min(bins_x_ - 1, static_cast<int>((r.x + rad - bin_x0_) / bin_size_));
    const int j0 = std::max(0, static_cast<int>((r.y - rad - bin_y0_) / bin_size_));
    const int j1 = std::min(bins_y_ - 1, static_cast<int>((r.y + rad - bin_y0_) / bin_size_));
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) fn(static_cast<std::size_t>(j) * static_cast<std::size_t>(bins_x_) + static_cast<std::size_t>(i));
  };
  for (const Rock& r : rocks_) for_each_bin(r, [&](std::size_t b) { ++counts[b + 1]; });
  for (std::size_t b = 0; b < nbins; ++b) counts[b + 1] += counts[b];
  bin_start_ = counts;
  bin_items_.assign(static_cast<std::size_t>(counts[nbins]), 0);
  std::vector<int> fill(counts.begin(), counts.end() - 1);
  for (std::size_t k = 0; k < rocks_.size(); ++k) {
    for_each_bin(rocks_[k], [&](std::size_t b) { bin_items_[static_cast<std::size_t>(fill[b]++)] = static_cast<int>(k); });
  }
}

double ProceduralTerrain::rock_height(double x, double y) const {
  if (bins_x_ == 0) return 0.0;
  const double fx = (x - bin_x0_) / bin_size_, fy = (y - bin_y0_) / bin_size_;
  if (fx < 0.0 || fy < 0.0) return 0.0;
  const int i = static_cast<int>(fx), j = static_cast<int>(fy);
  if (i >= bins_x_ || j >= bins_y_) return 0.0;
  const std::size_t b = static_cast<std::size_t>(j) * static_cast<std::size_t>(bins_x_) + static_cast<std::size_t>(i);
  double best = 0.0;
  for (int k = bin_start_[b]; k < bin_start_[b + 1]; ++k) {
    const Rock& r = rocks_[static_cast<std::size_t>(bin_items_[static_cast<std::size_t>(k)])];
    const double rad = 0.5 * r.diameter_m;
    const double dx = x - r.x, dy = y - r.y;
    const double q = 1.0 - (dx * dx + dy * dy) / (rad * rad);
    if (q > 0.0) best = std::max(best, r.height_m * std::sqrt(q));
  }
  return best;
}

double ProceduralTerrain::obstacle_height(double x, double y) const {
  double best = rock_height(x, y);
  for (const Box& b : boxes_) {
    if (x >= b.x0 && x <= b.x1 && y >= b.y0 && y <= b.y1) best = std::max(best, b.height_m);
  }
  return best;
}

double ProceduralTerrain::ground_height(double x, double y) const {
  double h = params_.base_height_m + params_.slope_x * x + params_.slope_y * y;
  for (const Wave& w : waves_) h += w.amplitude * std::sin(w.kx * x + w.ky * y + w.phase);
  const RoughnessParams& rp = params_.roughness;
  double amplitude = rp.amplitude_m, frequency = 1.0 / rp.wavelength_m;
  for (int o = 0; o < rp.octaves; ++o) {
    h += amplitude * value_noise(x * frequency, y * frequency, hash_combine(params_.seed, 4, static_cast<std::uint64_t>(o)));
    amplitude *= rp.persistence;
    frequency *= 2.0;
  }
  for (const Crater& c : craters_) h += crater_profile(c, x, y);
  for (const Ditch& d : ditches_) {
    if (x >= d.x0 && x <= d.x1 && y >= d.y0 && y <= d.y1) h -= d.depth_m;
  }
  return h;
}

double ProceduralTerrain::height(double x, double y) const { return ground_height(x, y) + obstacle_height(x, y); }

// ---------------------------------------------------------------------------------------------

WaveTerrain::WaveTerrain(double amplitude_m, double wavelength_m, double direction_rad, double cross_amplitude_m,
                         double cross_wavelength_m)
    : amplitude_(amplitude_m),
      wavelength_(wavelength_m),
      cos_(std::cos(direction_rad)),
      sin_(std::sin(direction_rad)),
      cross_amplitude_(cross_amplitude_m),
      cross_wavelength_(cross_wavelength_m) {}

double WaveTerrain::height(double x, double y) const {
  const double s = x * cos_ + y * sin_;
  double h = amplitude_ * std::sin(2.0 * kPi * s / wavelength_);
  if (cross_amplitude_ != 0.0) {
    const double t = -x * sin_ + y * cos_;
    h += cross_amplitude_ * std::sin(2.0 * kPi * t / cross_wavelength_);
  }
  return h;
}

// ---------------------------------------------------------------------------------------------

HeightRaster::HeightRaster(double origin_x, double origin_y, double resolution_m, int nx, int ny, float fill)
    : ox_(origin_x), oy_(origin_y), res_(resolution_m), nx_(nx), ny_(ny),
      h_(static_cast<std::size_t>(std::max(0, nx)) * static_cast<std::size_t>(std::max(0, ny)), fill) {}

double HeightRaster::height(double x, double y) const {
  if (nx_ < 2 || ny_ < 2) return kNaN;
  const double fx = (x - ox_) / res_, fy = (y - oy_) / res_;
  if (!(fx >= 0.0 && fy >= 0.0 && fx <= nx_ - 1 && fy <= ny_ - 1)) return kNaN;
  int i = static_cast<int>(fx), j = static_cast<int>(fy);
  if (i > nx_ - 2) i = nx_ - 2;
  if (j > ny_ - 2) j = ny_ - 2;
  const double tx = fx - i, ty = fy - j;
  const float* row0 = &h_[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx_) + static_cast<std::size_t>(i)];
  const float* row1 = row0 + nx_;
  const double a = row0[0] + (row0[1] - row0[0]) * tx;
  const double b = row1[0] + (row1[1] - row1[0]) * tx;
  return a + (b - a) * ty;  // NaN propagates from no-data vertices
}

void HeightRaster::shift_heights(double dz) {
  for (float& v : h_) {
    if (std::isfinite(v)) v = static_cast<float>(v + dz);
  }
  if (!bmax_.empty()) build_blocks(block_);
}

double HeightRaster::min_height() const {
  double m = kNaN;
  for (float v : h_) if (std::isfinite(v) && !(v >= m)) m = v;
  return m;
}

double HeightRaster::max_height() const {
  double m = kNaN;
  for (float v : h_) if (std::isfinite(v) && !(v <= m)) m = v;
  return m;
}

double HeightRaster::mean_height() const {
  double s = 0.0;
  std::size_t n = 0;
  for (float v : h_) {
    if (std::isfinite(v)) {
      s += v;
      ++n;
    }
  }
  return n > 0 ? s / static_cast<double>(n) : kNaN;
}

void HeightRaster::build_blocks(int block_size) {
  block_ = std::max(1, block_size);
  if (nx_ < 2 || ny_ < 2) {
    bx_ = by_ = 0;
    bmax_.clear();
    return;
  }
  // Block (bx, by) covers cells [bx*B, (bx+1)*B) i.e. vertices [bx*B, (bx+1)*B] inclusive.
  bx_ = (nx_ - 2) / block_ + 1;
  by_ = (ny_ - 2) / block_ + 1;
  bmax_.assign(static_cast<std::size_t>(bx_) * static_cast<std::size_t>(by_), -std::numeric_limits<float>::infinity());
  for (int b = 0; b < by_; ++b) {
    for (int a = 0; a < bx_; ++a) {
      const float m = scan_block(a, b);
      bmax_[static_cast<std::size_t>(b) * static_cast<std::size_t>(bx_) + static_cast<std::size_t>(a)] = m;
    }
  }
  blocks_max_ = -std::numeric_limits<float>::infinity();
  for (float m : bmax_) blocks_max_ = std::max(blocks_max_, m);
}

float HeightRaster::scan_block(int a, int b) const {
  // The block's vertices and the next block's first row and column (a cell's four corners);
  // +inf if any is not finite (nothing below it may be trusted).
  float m = -std::numeric_limits<float>::infinity();
  const int i1 = std::min(nx_ - 1, (a + 1) * block_), j1 = std::min(ny_ - 1, (b + 1) * block_);
  for (int j = b * block_; j <= j1; ++j) {
    for (int i = a * block_; i <= i1; ++i) {
      const float v = at(i, j);
      m = std::isfinite(v) ? std::max(m, v) : std::numeric_limits<float>::infinity();
    }
  }
  return m;
}

void HeightRaster::rebuild_blocks(const Rect& area) {
  if (bmax_.empty() || bx_ == 0 || by_ == 0) return;
  const auto block_of = [&](double v, double origin, int count) {
    const int b = static_cast<int>(std::floor((v - origin) / res_)) / block_;
    return std::clamp(b, 0, count - 1);
  };
  // A vertex on a block boundary belongs to two blocks: widen by one block on each side.
  const int a0 = std::max(0, block_of(area.x0, ox_, bx_) - 1), a1 = std::min(bx_ - 1, block_of(area.x1, ox_, bx_) + 1);
  const int b0 = std::max(0, block_of(area.y0, oy_, by_) - 1), b1 = std::min(by_ - 1, block_of(area.y1, oy_, by_) + 1);
  for (int b = b0; b <= b1; ++b) {
    for (int a = a0; a <= a1; ++a) {
      const float m = scan_block(a, b);
      bmax_[static_cast<std::size_t>(b) * static_cast<std::size_t>(bx_) + static_cast<std::size_t>(a)] = m;
      blocks_max_ = std::max(blocks_max_, m);
    }
  }
}

HeightRaster rasterize(const Terrain& terrain, const Rect& area, double resolution_m, HeightRaster* ground) {
  const int nx = static_cast<int>(std::floor(area.width() / resolution_m + 1e-9)) + 1;
  const int ny = static_cast<int>(std::floor(area.height() / resolution_m + 1e-9)) + 1;
  HeightRaster out(area.x0, area.y0, resolution_m, nx, ny);
  if (ground != nullptr) *ground = HeightRaster(area.x0, area.y0, resolution_m, nx, ny);
  for (int j = 0; j < ny; ++j) {
    const double y = area.y0 + j * resolution_m;
    for (int i = 0; i < nx; ++i) {
      const double x = area.x0 + i * resolution_m;
      out.at(i, j) = static_cast<float>(terrain.height(x, y));
      if (ground != nullptr) ground->at(i, j) = static_cast<float>(terrain.ground_height(x, y));
    }
  }
  out.build_blocks();
  if (ground != nullptr) ground->build_blocks();
  return out;
}

bool load_esri_ascii(const std::string& path, HeightRaster* out, std::string* error) {
  auto fail = [error](const std::string& m) {
    if (error != nullptr) *error = m;
    return false;
  };
  std::ifstream in(path);
  if (!in) return fail("cannot open " + path);
  int ncols = -1, nrows = -1;
  double xll = 0.0, yll = 0.0, cellsize = -1.0, nodata = kNaN;
  bool x_center = false, y_center = false;
  // Header: key value pairs until the first numeric token.
  std::string key;
  std::streampos data_start = in.tellg();
  while (in >> key) {
    std::string lower = key;
    std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (!lower.empty() && (std::isdigit(static_cast<unsigned char>(lower[0])) || lower[0] == '-' || lower[0] == '.' || lower[0] == '+')) {
      break;
    }
    double value = 0.0;
    if (!(in >> value)) return fail("bad header value for " + key + " in " + path);
    if (lower == "ncols") ncols = static_cast<int>(value);
    else if (lower == "nrows") nrows = static_cast<int>(value);
    else if (lower == "xllcorner") xll = value;
    else if (lower == "xllcenter") { xll = value; x_center = true; }
    else if (lower == "yllcorner") yll = value;
    else if (lower == "yllcenter") { yll = value; y_center = true; }
    else if (lower == "cellsize") cellsize = value;
    else if (lower == "nodata_value") nodata = value;
    else return fail("unknown header key " + key + " in " + path);
    data_start = in.tellg();
  }
  if (ncols < 2 || nrows < 2 || !(cellsize > 0.0)) return fail("incomplete header (ncols, nrows, cellsize) in " + path);
  in.clear();
  in.seekg(data_start);
  const double x0 = x_center ? xll : xll + 0.5 * cellsize;
  const double y0 = y_center ? yll : yll + 0.5 * cellsize;
  HeightRaster r(x0, y0, cellsize, ncols, nrows);
  for (int row = 0; row < nrows; ++row) {
    const int j = nrows - 1 - row;  // first data row is the north edge
    for (int i = 0; i < ncols; ++i) {
      double v = 0.0;
      if (!(in >> v)) {
        std::ostringstream m;
        m << path << ": expected " << ncols * nrows << " values, got " << row * ncols + i;
        return fail(m.str());
      }
      const bool no_data = std::isfinite(nodata) && std::fabs(v - nodata) <= 1e-6 * std::fabs(nodata);
      r.at(i, j) = no_data ? std::numeric_limits<float>::quiet_NaN() : static_cast<float>(v);
    }
  }
  r.build_blocks();
  *out = std::move(r);
  return true;
}

}  // namespace ccmap::sim
