// Host adapter between the ccmap command-line tool and the library's Stack<Config> templates:
// one run-time polymorphic interface over the presets, in the library's local float frame
// (metres relative to the origin the tool chose). Nothing here knows about files or absolute
// coordinates.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace ccmap::tools {

enum class SensorChoice : std::uint8_t {
  kLidar,        ///< constant range noise (sigma_m), e.g. a terrestrial or mobile laser scan
  kCadreStereo,  ///< the CADRE stereo model: noise grows with range^2 from the sensor origin
};

struct RunnerOptions {
  std::string preset;                     ///< cadre, ccm, kf, omg
  double finest_cell_width_m = 0.0;       ///< <= 0: the preset's default
  double weight_limit = 0.0;              ///< <= 0: the library default
  SensorChoice sensor = SensorChoice::kLidar;
  double lidar_sigma_m = 0.005;           ///< range noise of the lidar model (m)
  /// The library's outlier gate in standard deviations (docs/design.md, "Outlier gate and
  /// change"); 0: off, the paper's update. Off by default here: a file is one frame, and the
  /// gate judges at most Stack::kCcmHeldSlots cells per frame (the rest of a whole scan's held
  /// points would be dropped as "pool full").
  double outlier_gate_sigma = 0.0;
};

/// Per-frame point accounting (the library's FrameCounters).
struct FrameStats {
  std::uint64_t received = 0, used = 0, rejected_non_finite = 0, rejected_out_of_range = 0,
                rejected_weight = 0, outside_map = 0, too_noisy = 0;
  /// Outlier gate: points it judged (dropped by the finer layer or the line of sight, held, or
  /// dropped with the held-point pool full), and held points the change rule admitted later.
  std::uint64_t gated = 0, gated_admitted = 0;
  void add(const FrameStats& o) {
    received += o.received; used += o.used; rejected_non_finite += o.rejected_non_finite;
    rejected_out_of_range += o.rejected_out_of_range; rejected_weight += o.rejected_weight;
    outside_map += o.outside_map; too_noisy += o.too_noisy;
    gated += o.gated; gated_admitted += o.gated_admitted;
  }
};

/// One exported cell in the local frame (library units).
struct LocalCell {
  std::int32_t ix = 0, iy = 0;  ///< library global index (relative to the local origin)
  float centre_x = 0, centre_y = 0, weight = 0, height = 0, slope_x = 0, slope_y = 0;
  float normal_variance = 0, elevation_variance = 0;
  const char* cell_class = "unknown";
};

struct LocalQuery {
  std::string status;           ///< ok, unknown, outside_map, ...
  int layer = -1;
  float cell_width = 0, height = 0, slope_x = 0, slope_y = 0, inclination = 0;
  float normal_variance = 0, elevation_variance = 0, weight = 0;
  const char* cell_class = "unknown";
  bool upset = false;  ///< QueryResult::upset: unknown because the cell failed its check (an upset)
};

/// A footprint query's answer (planner/footprint.hpp) in the local frame.
struct LocalFootprint {
  std::string status;               ///< ok, outside_map, or the refusal
  const char* worst_class = "unknown";
  const char* verdict = "unknown";  ///< footprint_class() with the caller's unknown share
  float unknown_share = 1, upset_share = 0, max_step = 0, max_inclination = 0, min_height = 0, max_height = 0;
  std::uint32_t cells_visited = 0;
};

/// A path query's answer (planner/path_query.hpp) in the local frame.
struct LocalPath {
  std::string status;
  bool hazard = false, unknown = false;
  float first_hazard_m = 0, first_unknown_m = 0, hazard_x = 0, hazard_y = 0, unknown_x = 0, unknown_y = 0;
  const char* hazard_class = "unknown";
  float length_m = 0;
  std::uint32_t poses = 0;
};

/// A registration's or alignment's answer (registration/types.hpp) in the local frame.
struct LocalCorrection {
  std::string status;           ///< ok, or why nothing is claimed
  double correction[4] = {0, 0, 0, 0};  ///< dx, dy, dz (m), dyaw (rad)
  double sigma[4] = {0, 0, 0, 0};       ///< +inf where not observable
  bool observable[4] = {false, false, false, false};
  std::uint32_t iterations = 0, matched = 0, cells = 0;
  double centre[2] = {0, 0};    ///< rotation centre, local metres
};

class MapRunner {
 public:
  virtual ~MapRunner() = default;
  /// Configures the stack; false with a one-line reason.
  virtual bool init(const RunnerOptions& options, std::string* error) = 0;
  /// Empties the map: every cell unobserved, windows centred on the local origin, counters
  /// zero, the parameters of init() (its calibrated normal-variance thresholds reused, so a
  /// reset costs a clear of the cells, not a calibration). False before a successful init().
  virtual bool reset(std::string* error) = 0;
  /// Re-centres the stack on (x, y), local metres.
  virtual bool move_to(float x, float y, std::string* error) = 0;
  /// Folds one frame (xyz interleaved, local metres); sensor origin in local metres. `weights`
  /// is empty (the sensor model weighs the points) or one weight per point.
  virtual bool update_frame(const std::vector<float>& xyz, const std::vector<float>& weights,
                            const float sensor_origin[3], FrameStats* stats, std::string* error) = 0;
  virtual int layer_count() const = 0;
  virtual float layer_cell_width(int layer) const = 0;
  virtual int layer_side(int layer) const = 0;                 ///< cells per axis
  virtual bool layer_is_ccm(int layer) const = 0;
  virtual float layer_normal_variance_threshold(int layer) const = 0;
  /// Lowest global index (x, y) of the layer's window.
  virtual void layer_window_min(int layer, std::int32_t* ix, std::int32_t* iy) const = 0;
  virtual bool export_layer(int layer, std::vector<LocalCell>* cells, std::string* error) const = 0;
  virtual LocalQuery query(float x, float y) const = 0;
  /// The footprint query of the rectangle centred (x, y), length axis along (hx, hy).
  virtual LocalFootprint footprint(float x, float y, float hx, float hy, float length, float width,
                                   float max_unknown_share) const = 0;
  /// The path query along the polyline xy (x0 y0 x1 y1 ...), the body every `step` m.
  virtual LocalPath path(const std::vector<float>& xy, float length, float width, float step,
                         float max_unknown_share) const = 0;
  /// The stack's maximum inclination (dz/dxy): the steep limit the cost function scales by.
  virtual float max_inclination() const = 0;
  virtual FrameStats totals() const = 0;
  virtual float weight_limit() const = 0;
  virtual float min_weight() const = 0;
  /// Bytes of a snapshot of this preset.
  virtual std::size_t snapshot_size() const = 0;
  /// The library's snapshot of the map (save_snapshot).
  virtual bool save_snapshot(std::vector<std::uint8_t>* bytes, std::string* error) const = 0;
  /// Replaces the map by a snapshot (load_snapshot: parameters, windows, cells).
  virtual bool load_snapshot(const std::vector<std::uint8_t>& bytes, std::string* error) = 0;
  /// Registers a frame (xyz interleaved, local metres; sensor origin) against the map before it
  /// is folded in (register_frame(stack, ...), default parameters): the map is unchanged.
  virtual LocalCorrection register_frame(const std::vector<float>& xyz, const float sensor_origin[3]) = 0;
  /// Team alignment (align_snapshot) of another map's snapshot placed by offset_m (its origin
  /// minus this one's, local metres): the defaults with a +-2 m, +-0.5 rad search in 40 iterations.
  virtual LocalCorrection align_snapshot(const std::vector<std::uint8_t>& bytes, const double offset_m[3]) const = 0;
  /// Folds a snapshot of another map into this one (merge_snapshot); offset: that map's origin
  /// minus this one's, in finest cells (a multiple of the coarsest layer's) and metres (z).
  virtual bool merge_snapshot(const std::vector<std::uint8_t>& bytes, std::int32_t offset_x_cells,
                              std::int32_t offset_y_cells, float offset_z_m, std::uint64_t* merged,
                              std::uint64_t* outside, std::string* error) = 0;
};

/// Preset names, in the order shown by --help.
const std::vector<std::string>& preset_names();
/// Default finest cell width of a preset (m); 0 for an unknown preset.
double preset_default_cell_width(const std::string& preset);
/// Number of layers of a preset; 0 for an unknown preset.
int preset_layer_count(const std::string& preset);
/// True if the preset has CCM layers (cadre, ccm).
bool preset_has_ccm(const std::string& preset);
/// A runner for the preset, not yet initialised: full CCM cells, or the paper's 9-float cells
/// with paper_cell (PaperCell<Config>). nullptr with a message for an unknown preset, or for
/// paper_cell with a preset without CCM layers.
std::unique_ptr<MapRunner> make_map_runner(const std::string& preset, bool paper_cell, std::string* error);
/// The same with full CCM cells.
std::unique_ptr<MapRunner> make_map_runner(const std::string& preset, std::string* error);

}  // namespace ccmap::tools
