#include "map_runner.hpp"

#include <cmath>

#include "ccmap/map/config.hpp"
#include "ccmap/planner/footprint.hpp"
#include "ccmap/planner/path_query.hpp"
#include "ccmap/persistence/exchange.hpp"
#include "ccmap/persistence/snapshot.hpp"
#include "ccmap/map/stack.hpp"
#include "ccmap/registration/alignment.hpp"
#include "ccmap/registration/registration.hpp"
#include "ccmap/sensor/noise_model.hpp"

namespace ccmap::tools {
namespace {

LocalCorrection to_local(const RegistrationResult& r, float centre_x, float centre_y, std::uint32_t cells) {
  LocalCorrection c;
  c.status = to_string(r.status);
  const float v[4] = {r.dx, r.dy, r.dz, r.dyaw};
  const float s[4] = {r.sigma_dx, r.sigma_dy, r.sigma_dz, r.sigma_dyaw};
  for (int k = 0; k < 4; ++k) {
    c.correction[k] = v[k];
    c.sigma[k] = s[k];
    c.observable[k] = r.observable[k];
  }
  c.iterations = r.iterations;
  c.matched = r.points_matched;
  c.cells = cells;
  c.centre[0] = centre_x;
  c.centre[1] = centre_y;
  return c;
}

FrameStats to_stats(const FrameCounters& c) {
  FrameStats s;
  s.received = c.received;
  s.used = c.used;
  s.rejected_non_finite = c.rejected_non_finite;
  s.rejected_out_of_range = c.rejected_out_of_range;
  s.rejected_weight = c.rejected_weight;
  s.outside_map = c.outside_map;
  s.too_noisy = c.too_noisy;
  s.gated = std::uint64_t{c.gated_finer} + c.gated_occluded + c.gated_held + c.gated_pool_full;
  s.gated_admitted = c.gated_admitted;
  return s;
}

template <typename Config>
class StackRunner final : public MapRunner {
 public:
  using StackType = Stack<Config>;

  bool init(const RunnerOptions& options, std::string* error) override {
    const float width = options.finest_cell_width_m > 0.0 ? static_cast<float>(options.finest_cell_width_m)
                                                          : Config::kDefaultFinestCellWidthM;
    StackParams params = default_stack_params(width);
    if (options.weight_limit > 0.0) params.weight_limit = static_cast<float>(options.weight_limit);
    params.outlier_gate_sigma = static_cast<float>(options.outlier_gate_sigma);
    // Free space from lines of sight needs the scanner's position: a file's frame comes with a
    // nominal origin (the tile's centre, the pose's ground point), so its lines of sight would
    // clear and bound the wrong cells. Off here (docs/design.md, "Free space from lines of sight").
    params.free_space_rays = 0.0F;
    if (options.sensor == SensorChoice::kLidar) {
      params.noise = sensor::NoiseModel::lidar(sensor::LidarParams{static_cast<float>(options.lidar_sigma_m), 0.0F});
    }
    const Status status = stack_->init(params);
    if (status != Status::kOk) {
      *error = std::string("the map refused its parameters (") + to_string(status) + ")";
      return false;
    }
    params_ = params;
    for (int layer = 0; layer < StackType::kLayerCount; ++layer) {
      params_.normal_variance_threshold[static_cast<std::size_t>(layer)] = stack_->normal_variance_threshold(layer);
    }
    return true;
  }

  bool reset(std::string* error) override {
    const Status status = stack_->initialised() ? stack_->init(params_) : Status::kNotInitialised;
    if (status != Status::kOk) {
      *error = std::string("cannot reset the map (") + to_string(status) + ")";
      return false;
    }
    return true;
  }

  bool move_to(float x, float y, std::string* error) override {
    const Status status = stack_->move_to(x, y);
    if (status != Status::kOk) {
      *error = std::string("cannot move the map (") + to_string(status) + ")";
      return false;
    }
    return true;
  }

  bool update_frame(const std::vector<float>& xyz, const std::vector<float>& weights, const float sensor_origin[3],
                    FrameStats* stats, std::string* error) override {
    points_.resize(xyz.size() / 3U);
    for (std::size_t i = 0; i < points_.size(); ++i) {
      points_[i] = PointXYZ{xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]};
    }
    FrameCounters counters{};
    const PointXYZ origin{sensor_origin[0], sensor_origin[1], sensor_origin[2]};
    const float* w = weights.size() == points_.size() && !weights.empty() ? weights.data() : nullptr;
    const Status status = stack_->update_frame(points_.data(), w, points_.size(), origin, &counters);
    if (status != Status::kOk) {
      *error = std::string("the map refused the frame (") + to_string(status) + ")";
      return false;
    }
    *stats = to_stats(counters);
    return true;
  }

  int layer_count() const override { return StackType::kLayerCount; }
  float layer_cell_width(int layer) const override { return stack_->layer_cell_width(layer); }
  int layer_side(int layer) const override { return StackType::layer_side(layer); }
  bool layer_is_ccm(int layer) const override { return StackType::layer_is_ccm(layer); }
  float layer_normal_variance_threshold(int layer) const override {
    return stack_->normal_variance_threshold(layer);
  }
  void layer_window_min(int layer, std::int32_t* ix, std::int32_t* iy) const override {
    const CellIndex centre = stack_->layer_centre(layer);
    const std::int32_t half = StackType::layer_side(layer) / 2;
    *ix = centre.x - half;
    *iy = centre.y - half;
  }

  bool export_layer(int layer, std::vector<LocalCell>* cells, std::string* error) const override {
    std::vector<CellRecord> records(StackType::layer_capacity(layer));
    std::size_t written = 0;
    const Status status = stack_->export_layer(layer, records.data(), records.size(), &written);
    if (status != Status::kOk) {
      *error = "cannot export layer " + std::to_string(layer) + " (" + to_string(status) + ")";
      return false;
    }
    cells->clear();
    cells->reserve(written);
    for (std::size_t i = 0; i < written; ++i) {
      const CellRecord& r = records[i];
      LocalCell c;
      c.ix = r.index.x;
      c.iy = r.index.y;
      c.centre_x = r.centre_x;
      c.centre_y = r.centre_y;
      c.weight = r.weight;
      c.height = r.height_m;
      c.slope_x = r.slope_x;
      c.slope_y = r.slope_y;
      c.normal_variance = r.normal_variance;
      c.elevation_variance = r.elevation_variance;
      c.cell_class = to_string(r.cell_class);
      cells->push_back(c);
    }
    return true;
  }

  LocalQuery query(float x, float y) const override {
    const QueryResult q = stack_->query(x, y);
    LocalQuery out;
    out.status = to_string(q.status);
    out.layer = q.layer;
    out.cell_width = q.cell_width_m;
    out.height = q.height_m;
    out.slope_x = q.slope_x;
    out.slope_y = q.slope_y;
    out.inclination = q.inclination;
    out.normal_variance = q.normal_variance;
    out.elevation_variance = q.elevation_variance;
    out.weight = q.weight;
    out.cell_class = to_string(q.cell_class);
    out.upset = q.upset;
    return out;
  }

  LocalFootprint footprint(float x, float y, float hx, float hy, float length, float width,
                           float max_unknown_share) const override {
    const FootprintResult r = query_footprint(*stack_, Footprint{x, y, hx, hy, length, width});
    LocalFootprint out;
    out.status = to_string(r.status);
    out.worst_class = to_string(r.worst_class);
    out.verdict = to_string(footprint_class(r, max_unknown_share));
    out.unknown_share = r.unknown_share;
    out.upset_share = r.upset_share;
    out.max_step = r.max_step_m;
    out.max_inclination = r.max_inclination;
    out.min_height = r.min_height_m;
    out.max_height = r.max_height_m;
    out.cells_visited = r.cells_visited;
    return out;
  }

  LocalPath path(const std::vector<float>& xy, float length, float width, float step,
                 float max_unknown_share) const override {
    std::vector<PathPoint> points(xy.size() / 2U);
    for (std::size_t i = 0; i < points.size(); ++i) points[i] = PathPoint{xy[2 * i], xy[2 * i + 1]};
    const PathResult r =
        query_path(*stack_, points.data(), points.size(), PathSweep{length, width, step, max_unknown_share});
    LocalPath out;
    out.status = to_string(r.status);
    out.hazard = r.hazard_found;
    out.unknown = r.unknown_found;
    out.first_hazard_m = r.first_hazard_m;
    out.first_unknown_m = r.first_unknown_m;
    out.hazard_x = r.hazard_pose.x;
    out.hazard_y = r.hazard_pose.y;
    out.unknown_x = r.unknown_pose.x;
    out.unknown_y = r.unknown_pose.y;
    out.hazard_class = to_string(r.hazard.worst_class);
    out.length_m = r.path_length_m;
    out.poses = r.samples;
    return out;
  }

  float max_inclination() const override { return stack_->params().max_inclination; }

  FrameStats totals() const override { return to_stats(stack_->total_counters()); }
  float weight_limit() const override { return stack_->params().weight_limit; }
  float min_weight() const override { return stack_->params().min_weight; }

  std::size_t snapshot_size() const override { return ccmap::snapshot_size<Config>(); }

  bool save_snapshot(std::vector<std::uint8_t>* bytes, std::string* error) const override {
    bytes->assign(ccmap::snapshot_size<Config>(), 0U);
    std::size_t written = 0;
    const Status status = ccmap::save_snapshot(*stack_, bytes->data(), bytes->size(), &written);
    if (status != Status::kOk) {
      *error = std::string("cannot save the map (") + to_string(status) + ")";
      return false;
    }
    return true;
  }

  bool load_snapshot(const std::vector<std::uint8_t>& bytes, std::string* error) override {
    const Status status = ccmap::load_snapshot(*stack_, bytes.data(), bytes.size());
    if (status != Status::kOk) {
      *error = std::string("the map does not load (") + to_string(status) + ")";
      return false;
    }
    return true;
  }

  LocalCorrection register_frame(const std::vector<float>& xyz, const float sensor_origin[3]) override {
    points_.resize(xyz.size() / 3U);
    for (std::size_t i = 0; i < points_.size(); ++i) {
      points_[i] = PointXYZ{xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]};
    }
    const PointXYZ origin{sensor_origin[0], sensor_origin[1], sensor_origin[2]};
    return to_local(ccmap::register_frame(*stack_, points_.data(), points_.size(), origin, default_registration_params()),
                    origin.x, origin.y, 0U);
  }

  LocalCorrection align_snapshot(const std::vector<std::uint8_t>& bytes, const double offset_m[3]) const override {
    const MapOffset offset{static_cast<float>(offset_m[0]), static_cast<float>(offset_m[1]), static_cast<float>(offset_m[2])};
    // Maps of two rovers may be farther apart than two frames: a wider search, more iterations.
    RegistrationParams params = default_registration_params();
    params.max_translation_m = 2.0F;
    params.max_yaw_rad = 0.5F;
    params.max_iterations = 40U;
    const AlignmentResult a = ccmap::align_snapshot(*stack_, bytes.data(), bytes.size(), offset, params);
    return to_local(a.correction, a.centre_x_m, a.centre_y_m, a.cells);
  }

  bool merge_snapshot(const std::vector<std::uint8_t>& bytes, std::int32_t offset_x_cells, std::int32_t offset_y_cells,
                      float offset_z_m, std::uint64_t* merged, std::uint64_t* outside, std::string* error) override {
    MergeReport report{};
    const Status status = ccmap::merge_snapshot(*stack_, bytes.data(), bytes.size(),
                                                CellIndex{offset_x_cells, offset_y_cells}, offset_z_m, &report);
    if (status != Status::kOk) {
      *error = std::string("the map does not merge (") + to_string(status) + ")";
      return false;
    }
    *merged = report.cells_merged;
    *outside = report.cells_outside;
    return true;
  }

 private:
  std::unique_ptr<StackType> stack_ = std::make_unique<StackType>();  // MBs: never on the stack
  StackParams params_{};  ///< what init() accepted, thresholds as calibrated (for reset)
  std::vector<PointXYZ> points_;
};

struct PresetInfo {
  const char* name;
  double default_width;
  int layers;
};
const PresetInfo kPresets[] = {
    {"cadre", static_cast<double>(CadreConfig::kDefaultFinestCellWidthM), Stack<CadreConfig>::kLayerCount},
    {"ccm", static_cast<double>(SingleCcmConfig::kDefaultFinestCellWidthM), Stack<SingleCcmConfig>::kLayerCount},
    {"kf", static_cast<double>(SingleKalmanConfig::kDefaultFinestCellWidthM), Stack<SingleKalmanConfig>::kLayerCount},
    {"omg", static_cast<double>(SingleOmgConfig::kDefaultFinestCellWidthM), Stack<SingleOmgConfig>::kLayerCount},
};

}  // namespace

const std::vector<std::string>& preset_names() {
  static const std::vector<std::string> names = {"cadre", "ccm", "kf", "omg"};
  return names;
}

double preset_default_cell_width(const std::string& preset) {
  for (const PresetInfo& p : kPresets) {
    // The float defaults (0.04F, 0.08F) as the decimal the user would type.
    if (preset == p.name) return std::round(p.default_width * 1e6) / 1e6;
  }
  return 0.0;
}

int preset_layer_count(const std::string& preset) {
  for (const PresetInfo& p : kPresets) {
    if (preset == p.name) return p.layers;
  }
  return 0;
}

bool preset_has_ccm(const std::string& preset) { return preset == "cadre" || preset == "ccm"; }

std::unique_ptr<MapRunner> make_map_runner(const std::string& preset, bool paper_cell, std::string* error) {
  if (paper_cell && preset_layer_count(preset) > 0 && !preset_has_ccm(preset)) {
    *error = "--paper-cell: preset '" + preset + "' has no CCM layer (the option applies to cadre and ccm)";
    return nullptr;
  }
  if (preset == "cadre") {
    if (paper_cell) return std::make_unique<StackRunner<PaperCell<CadreConfig>>>();
    return std::make_unique<StackRunner<CadreConfig>>();
  }
  if (preset == "ccm") {
    if (paper_cell) return std::make_unique<StackRunner<PaperCell<SingleCcmConfig>>>();
    return std::make_unique<StackRunner<SingleCcmConfig>>();
  }
  if (preset == "kf") return std::make_unique<StackRunner<SingleKalmanConfig>>();
  if (preset == "omg") return std::make_unique<StackRunner<SingleOmgConfig>>();
  *error = "unknown preset '" + preset + "' (expected one of: cadre, ccm, kf, omg)";
  return nullptr;
}

std::unique_ptr<MapRunner> make_map_runner(const std::string& preset, std::string* error) {
  return make_map_runner(preset, false, error);
}

}  // namespace ccmap::tools
