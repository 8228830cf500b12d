// Simulated and measured terrains: height fields that can be sampled at any (x, y).
//
// Frames and units: x, y, z in metres in the terrain's own "world" frame (z up). Every
// terrain answers height(x, y) (the surface, what a sensor sees) and ground_height(x, y) (the
// surface without discrete obstacles such as rocks and boxes; equal to height() for terrains
// that have none). Outside its support a terrain returns NaN.
//
// Terrains provided:
//  - ProceduralTerrain: planar slope + rolling ground (a few long sinusoids) + fractal value
//    noise + craters (bowl and raised rim) + ditches (flat-floored trenches with vertical walls),
//    plus discrete obstacles: rocks as half-ellipsoid domes with a lunar-like power-law
//    size-frequency distribution, and flat-topped boxes. Craters and ditches are the negative
//    obstacles: negative_depth() says how far the surface lies below the ground without them.
//  - WaveTerrain: sinusoidal waves (the drift experiment's worst case, paper Section V-D).
//  - HeightRaster: a regular grid of heights sampled bilinearly; the ray caster's input (with
//    a block-maximum acceleration grid), the output of rasterize(), and the ESRI ASCII DTM
//    loader's result.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace ccmap::sim {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
inline constexpr double kPi = 3.14159265358979323846;

/// Axis-aligned rectangle [x0, x1] x [y0, y1] (m).
struct Rect {
  double x0 = 0.0, y0 = 0.0, x1 = 0.0, y1 = 0.0;
  double width() const { return x1 - x0; }
  double height() const { return y1 - y0; }
  double area() const { return width() * height(); }
  bool contains(double x, double y) const { return x >= x0 && x <= x1 && y >= y0 && y <= y1; }
};

class Terrain {
 public:
  virtual ~Terrain() = default;
  /// Surface height (m) at (x, y); NaN outside the terrain.
  virtual double height(double x, double y) const = 0;
  /// Height without discrete obstacles (rocks, boxes): the "local ground" of the hazard
  /// ground truth. Default: the surface itself.
  virtual double ground_height(double x, double y) const { return height(x, y); }
};

// ---------------------------------------------------------------------------------------------
// Procedural terrain
// ---------------------------------------------------------------------------------------------

/// Rolling ground: `waves` sinusoids with random directions and phases, wavelengths uniform in
/// [min_wavelength_m, max_wavelength_m]; each has amplitude amplitude_m / sqrt(waves) * U(0.5, 1)
/// so the total standard deviation is of the order of amplitude_m / 2.
struct RollingParams {
  int waves = 0;
  double amplitude_m = 0.0;
  double min_wavelength_m = 8.0;
  double max_wavelength_m = 25.0;
};

/// Fractal roughness: `octaves` of value noise (quintic-smoothed lattice noise in [-1, 1]); the
/// first octave has lattice spacing wavelength_m and amplitude amplitude_m, each next octave
/// halves the spacing and multiplies the amplitude by persistence.
struct RoughnessParams {
  int octaves = 0;
  double amplitude_m = 0.0;
  double wavelength_m = 2.0;
  double persistence = 0.5;
};

/// Rocks: cumulative number per m^2 with diameter >= D is
///   N(>=D) = density_per_m2 * (D / min_diameter_m)^(-exponent)   for D in [min, max],
/// i.e. a truncated Pareto law (lunar-like for exponent ~2.5). Rock count = round(density *
/// area), positions uniform over the area, height = height_ratio * D (a half-ellipsoid dome
/// z = H sqrt(1 - (r/R)^2), R = D/2, sitting on the ground).
struct RockParams {
  double density_per_m2 = 0.0;
  double min_diameter_m = 0.1;
  double max_diameter_m = 1.0;
  double exponent = 2.5;
  double height_ratio = 0.5;
};

/// Craters: `count` craters with diameters log-uniform in [min, max], centres uniform over the
/// area. Profile with r = distance / R (R = D/2): bowl  h = -depth + (depth + rim) r^2  for r < 1,
/// rim falloff  h = rim (r^-3 - 2.5^-3) / (1 - 2.5^-3)  for 1 <= r < 2.5, 0 beyond;
/// depth = depth_ratio * D, rim = rim_ratio * D.
struct CraterParams {
  int count = 0;
  double min_diameter_m = 1.0;
  double max_diameter_m = 5.0;
  double depth_ratio = 0.15;
  double rim_ratio = 0.03;
};

struct TerrainParams {
  Rect area{0.0, 0.0, 20.0, 20.0};  ///< where rocks and craters are placed (height() is defined everywhere)
  double base_height_m = 0.0;
  double slope_x = 0.0;             ///< planar gradient dz/dx (dimensionless)
  double slope_y = 0.0;             ///< planar gradient dz/dy
  RollingParams rolling;
  RoughnessParams roughness;
  RockParams rocks;
  CraterParams craters;
  std::uint64_t seed = 1;
};

struct Rock {
  double x = 0.0, y = 0.0;   ///< centre (m)
  double diameter_m = 0.0;
  double height_m = 0.0;
};

/// Flat-topped axis-aligned box: inside [x0,x1]x[y0,y1] the surface is ground + height_m.
struct Box {
  double x0 = 0.0, y0 = 0.0, x1 = 0.0, y1 = 0.0;
  double height_m = 0.0;
};

struct Crater {
  double x = 0.0, y = 0.0, diameter_m = 0.0, depth_m = 0.0, rim_m = 0.0;
};

/// A trench: inside the axis-aligned rectangle [x0,x1]x[y0,y1] the ground lies depth_m lower
/// (a flat floor, vertical walls): a negative obstacle a rover sees only its far wall of.
struct Ditch {
  double x0 = 0.0, y0 = 0.0, x1 = 0.0, y1 = 0.0;
  double depth_m = 0.0;
};

/// A few examples with sensible values (documented in the .cpp).
TerrainParams lunar_terrain_params(const Rect& area, std::uint64_t seed);

class ProceduralTerrain : public Terrain {
 public:
  /// Flat terrain at height 0 with nothing on it.
  ProceduralTerrain();
  /// Generates rocks and craters from params (deterministic by params.seed).
  explicit ProceduralTerrain(const TerrainParams& params);

  double height(double x, double y) const override;
  double ground_height(double x, double y) const override;
  /// Height of discrete obstacles above the ground at (x, y): the max of the rock domes and
  /// boxes covering the point (they do not stack), 0 where there is none.
  double obstacle_height(double x, double y) const;
  /// How far the ground at (x, y) lies below the ground without craters and ditches (m, >= 0):
  /// the depth of a crater's bowl below its surroundings plus a ditch's depth; 0 elsewhere and
  /// on a crater's raised rim.
  double negative_depth(double x, double y) const;

  void add_rock(const Rock& rock);
  void add_box(const Box& box);
  void add_crater(const Crater& crater);
  void add_ditch(const Ditch& ditch);

  const std::vector<Rock>& rocks() const { return rocks_; }
  const std::vector<Box>& boxes() const { return boxes_; }
  const std::vector<Crater>& craters() const { return craters_; }
  const std::vector<Ditch>& ditches() const { return ditches_; }
  const TerrainParams& params() const { return params_; }

 private:
  struct Wave {
    double kx, ky, phase, amplitude;
  };
  void rebuild_rock_index();
  double rock_height(double x, double y) const;

  TerrainParams params_;
  std::vector<Wave> waves_;
  std::vector<Rock> rocks_;
  std::vector<Box> boxes_;
  std::vector<Crater> craters_;
  std::vector<Ditch> ditches_;
  // Rock spatial hash: bins of size bin_size_ over the rocks' bounding box, CSR layout.
  double bin_size_ = 1.0, bin_x0_ = 0.0, bin_y0_ = 0.0;
  int bins_x_ = 0, bins_y_ = 0;
  std::vector<int> bin_start_;
  std::vector<int> bin_items_;
};

/// Value noise in [-1, 1] on a unit lattice (quintic interpolation of hashed lattice values).
double value_noise(double x, double y, std::uint64_t seed);

// ---------------------------------------------------------------------------------------------
// Wave terrain (drift experiment)
// ---------------------------------------------------------------------------------------------

/// h = amplitude * sin(2 pi s / wavelength) with s = x cos(direction) + y sin(direction), plus
/// optionally a crossing wave along the perpendicular direction with its own amplitude.
class WaveTerrain : public Terrain {
 public:
  WaveTerrain(double amplitude_m, double wavelength_m, double direction_rad = 0.0,
              double cross_amplitude_m = 0.0, double cross_wavelength_m = 1.0);
  double height(double x, double y) const override;

 private:
  double amplitude_, wavelength_, cos_, sin_, cross_amplitude_, cross_wavelength_;
};

// ---------------------------------------------------------------------------------------------
// Height raster
// ---------------------------------------------------------------------------------------------

/// Heights on a regular vertex grid: vertex (i, j) is at (origin_x + i*res, origin_y + j*res),
/// i in [0, nx), j in [0, ny). height() interpolates bilinearly inside the grid's extent and
/// returns NaN outside it or next to a NaN (no-data) vertex.
class HeightRaster : public Terrain {
 public:
  HeightRaster() = default;
  HeightRaster(double origin_x, double origin_y, double resolution_m, int nx, int ny,
               float fill = 0.0F);

  double height(double x, double y) const override;

  int nx() const { return nx_; }
  int ny() const { return ny_; }
  double resolution() const { return res_; }
  double origin_x() const { return ox_; }
  double origin_y() const { return oy_; }
  Rect extent() const {
    return Rect{ox_, oy_, ox_ + (nx_ - 1) * res_, oy_ + (ny_ - 1) * res_};
  }
  bool empty() const { return nx_ < 2 || ny_ < 2; }
  float& at(int i, int j) { return h_[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx_) + static_cast<std::size_t>(i)]; }
  float at(int i, int j) const { return h_[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx_) + static_cast<std::size_t>(i)]; }
  /// Adds dz to every finite vertex (e.g. to bring a DTM's absolute elevation near 0).
  void shift_heights(double dz);
  /// Finite-vertex min / max / mean (NaN if none).
  double min_height() const;
  double max_height() const;
  double mean_height() const;

  /// (Re)builds the block-maximum grid used by the ray caster: the max vertex height of each
  /// block of block_size x block_size cells. Must be called after editing heights.
  void build_blocks(int block_size = 16);
  /// Rebuilds only the blocks whose vertices overlap `area` (after editing heights there; the
  /// block size stays). blocks_max() becomes an upper bound (it never decreases here).
  void rebuild_blocks(const Rect& area);
  int block_size() const { return block_; }
  int blocks_x() const { return bx_; }
  int blocks_y() const { return by_; }
  /// Max height within block (bx, by) (bilinear interpolation never exceeds its vertices);
  /// +inf if the block contains a NaN vertex.
  float block_max(int bx, int by) const { return bmax_[static_cast<std::size_t>(by) * static_cast<std::size_t>(bx_) + static_cast<std::size_t>(bx)]; }
  /// Max over all blocks (cached by build_blocks()).
  float blocks_max() const { return blocks_max_; }

 private:
  double ox_ = 0.0, oy_ = 0.0, res_ = 1.0;
  int nx_ = 0, ny_ = 0;
  std::vector<float> h_;
  int block_ = 16, bx_ = 0, by_ = 0;
  float scan_block(int a, int b) const;  ///< the maximum over block (a, b) (build_blocks, rebuild_blocks)
  std::vector<float> bmax_;
  float blocks_max_ = 0.0F;
};

/// Samples terrain.height() on a vertex grid covering `area` at resolution_m (the grid has
/// floor(width/res)+1 x floor(height/res)+1 vertices starting at (x0, y0)), builds its blocks.
/// `ground` (optional) receives the ground_height() raster on the same grid.
HeightRaster rasterize(const Terrain& terrain, const Rect& area, double resolution_m,
                       HeightRaster* ground = nullptr);

/// Loads an ESRI ASCII grid (ncols, nrows, xllcorner|xllcenter, yllcorner|yllcenter, cellsize,
/// optional NODATA_value; first data row = north). Cell values become vertices at the cell
/// centres (x = xllcorner + (i + 0.5) * cellsize, y = yllcorner + (j + 0.5) * cellsize, j counted
/// from the south); NODATA becomes NaN. Returns false with a reason in *error.
bool load_esri_ascii(const std::string& path, HeightRaster* out, std::string* error);

}  // namespace ccmap::sim
