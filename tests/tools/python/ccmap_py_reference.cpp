// Reference for the Python module's tests (tests/tools/python/test_reference.py): feeds fixed,
// deterministic frames to Stack<Config> directly, through the C++ API only (nothing of
// tools/python), and prints a transcript of every call and every answer. Floats are printed
// as their IEEE-754 bit patterns (8 hex digits), so the Python side replays the same inputs
// exactly and compares the answers bitwise.
//
//   ccmap_py_reference [SNAPSHOT_DIR]    transcript on stdout; SNAPSHOT_DIR/<scenario>.ccms
//                                        receives each scenario's final snapshot
//
// Transcript lines (tokens separated by one space; <f> = float bits, <name> = status/class):
//   map <scenario> <preset> [key=<f> | key=@word | key=[<f>,<f>,...]]...   (Python keywords)
//   move <fx> <fy> <status>
//   points <n> <with_weights 0|1>, then n lines "<fx> <fy> <fz> [<fw>]"
//   frame <ox> <oy> <oz> <status> <counter>=<n>...               (update_frame, map frame)
//   sensor_frame <r00> .. <r22> <tx> <ty> <tz> <status> <counter>=<n>...  (update_frame_sensor)
//   query <layer|-1> <fx> <fy> <field>=<value>...   (raw QueryResult; -1 = Stack::query)
//   upset <cells> <scrub_frames>   one bit flipped in each of <cells> live finest cells, then the
//         scrub's empty frames: from here the Python side reads the scenario's snapshot (Map.load)
//   layer <k> <count> <side> <centre_ix> <centre_iy> <width> <threshold>, then count lines
//         "<ix> <iy> <cx> <cy> <weight> <height> <slope_x> <slope_y> <normal_var> <elev_var> <class>"
//   totals <counter>=<n>...   rejected <moves> <frames>   snapshot <path>   end
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "ccmap/map/config.hpp"
#include "ccmap/map/detail/integrity.hpp"
#include "ccmap/map/stack.hpp"
#include "ccmap/persistence/snapshot.hpp"
#include "ccmap/planner/detail/region_walk.hpp"
#include "ccmap/sensor/noise_model.hpp"
#include "support/hash_unit.hpp"

namespace {

using ccmap::FrameCounters;
using ccmap::PointXYZ;
using ccmap::Status;
using ccmap::test::hash_unit;

std::string bits(float v) {
  std::uint32_t u = 0;
  std::memcpy(&u, &v, sizeof u);
  char buffer[16];
  std::snprintf(buffer, sizeof buffer, "%08x", u);
  return buffer;
}

void print_counters(const FrameCounters& c) {
  std::printf(" received=%u used=%u rejected_non_finite=%u rejected_out_of_range=%u rejected_weight=%u"
              " outside_map=%u too_noisy=%u gated_finer=%u gated_occluded=%u gated_held=%u gated_pool_full=%u gated_admitted=%u gated_dropped=%u reseeded_cells=%u"
              " merged_cells=%u skipped_budget=%u corrupted_cells=%u corrupted_slots=%u free_rays=%u"
              " free_rays_refused=%u cleared_cells=%u drop_cells=%u\n",
              c.received, c.used, c.rejected_non_finite, c.rejected_out_of_range, c.rejected_weight, c.outside_map,
              c.too_noisy, c.gated_finer, c.gated_occluded, c.gated_held, c.gated_pool_full, c.gated_admitted, c.gated_dropped, c.reseeded_cells,
              c.merged_cells, c.skipped_budget, c.corrupted_cells, c.corrupted_slots, c.free_rays, c.free_rays_refused,
              c.cleared_cells, c.drop_cells);
}
static_assert(sizeof(FrameCounters) == 22 * sizeof(std::uint32_t), "print every FrameCounters member");

/// Ground of the scenarios (map frame, m): a tilted plane, a 15 cm box, a 31 deg ramp.
double terrain(double x, double y) {
  double z = 0.04 * x - 0.07 * y;
  if (x > 1.5 && x < 1.8 && y > 0.3 && y < 0.6) z += 0.15;
  if (x > 3.0 && x < 3.5) z += 0.6 * (x - 3.0);
  return z;
}

struct Frame {
  std::vector<PointXYZ> points;
  std::vector<float> weights;  // empty: the noise model weighs
};

/// n points over [x0, x1] x [y0, y1] on terrain() plus up to +-1 mm of noise, with faults:
/// NaN, +Inf, beyond 1e5 m, far outside every window, and (for stereo) beyond every IV-G range.
/// weights (if asked) in [0.25, 4.25) with bad ones (0, negative, NaN, Inf, > 1e6) mixed in.
Frame make_frame(std::uint32_t salt, int n, double x0, double x1, double y0, double y1, bool weights) {
  Frame f;
  for (int i = 0; i < n; ++i) {
    const auto u = static_cast<std::uint32_t>(i);
    const double x = x0 + (x1 - x0) * hash_unit(u, salt);
    const double y = y0 + (y1 - y0) * hash_unit(u, salt + 1U);
    const double z = terrain(x, y) + 0.002 * (hash_unit(u, salt + 2U) - 0.5);
    PointXYZ p{static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)};
    if (i % 97 == 5) p.x = std::nanf("");
    if (i % 89 == 7) p.z = INFINITY;
    if (i % 83 == 9) p.y = 2.0e5F;
    if (i % 79 == 11) p.x = 60.0F;
    if (i % 73 == 13) p.x = 8.0F;
    f.points.push_back(p);
    if (weights) {
      float w = 0.25F + 4.0F * hash_unit(u, salt + 3U);
      if (i % 71 == 3) w = 0.0F;
      if (i % 67 == 4) w = -1.0F;
      if (i % 61 == 6) w = std::nanf("");
      if (i % 59 == 8) w = INFINITY;
      if (i % 53 == 10) w = 2.0e6F;
      f.weights.push_back(w);
    }
  }
  return f;
}

void print_points(const Frame& f) {
  std::printf("points %zu %d\n", f.points.size(), f.weights.empty() ? 0 : 1);
  for (std::size_t i = 0; i < f.points.size(); ++i) {
    const PointXYZ& p = f.points[i];
    if (f.weights.empty()) {
      std::printf("%s %s %s\n", bits(p.x).c_str(), bits(p.y).c_str(), bits(p.z).c_str());
    } else {
      std::printf("%s %s %s %s\n", bits(p.x).c_str(), bits(p.y).c_str(), bits(p.z).c_str(), bits(f.weights[i]).c_str());
    }
  }
}

template <typename Config>
class Scenario {
 public:
  using StackType = ccmap::Stack<Config>;

  Scenario(const std::string& name, const std::string& header, const ccmap::StackParams& params) : name_(name) {
    std::printf("map %s %s\n", name.c_str(), header.c_str());
    if (stack_->init(params) != Status::kOk) {
      std::fprintf(stderr, "%s: init refused\n", name.c_str());
      std::exit(1);
    }
  }

  void move(float x, float y) {
    const Status s = stack_->move_to(x, y);
    std::printf("move %s %s %s\n", bits(x).c_str(), bits(y).c_str(), ccmap::to_string(s));
  }

  void frame(const Frame& f, PointXYZ origin) {
    print_points(f);
    FrameCounters c{};
    const Status s = stack_->update_frame(f.points.data(), f.weights.empty() ? nullptr : f.weights.data(),
                                          f.points.size(), origin, &c);
    std::printf("frame %s %s %s %s", bits(origin.x).c_str(), bits(origin.y).c_str(), bits(origin.z).c_str(),
                ccmap::to_string(s));
    print_counters(c);
  }

  /// The map-frame points of `f` seen by a sensor yawed by `yaw_rad` at `t`: sensor-frame points
  /// p_s = R^T (p - t) (double, then float), folded in with update_frame_sensor.
  void sensor_frame(const Frame& f, double yaw_rad, PointXYZ t) {
    const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
    const float r[3][3] = {{static_cast<float>(c), static_cast<float>(-s), 0.0F},
                           {static_cast<float>(s), static_cast<float>(c), 0.0F},
                           {0.0F, 0.0F, 1.0F}};
    Frame sensor;
    for (const PointXYZ& p : f.points) {
      const double dx = static_cast<double>(p.x) - t.x, dy = static_cast<double>(p.y) - t.y,
                   dz = static_cast<double>(p.z) - t.z;
      sensor.points.push_back(PointXYZ{static_cast<float>(c * dx + s * dy), static_cast<float>(-s * dx + c * dy),
                                       static_cast<float>(dz)});
    }
    print_points(sensor);
    FrameCounters counters{};
    const Status status = stack_->update_frame_sensor(sensor.points.data(), sensor.points.size(), pose(r, t), &counters);
    std::printf("sensor_frame");
    for (const auto& row : r) {
      for (const float v : row) std::printf(" %s", bits(v).c_str());
    }
    std::printf(" %s %s %s %s", bits(t.x).c_str(), bits(t.y).c_str(), bits(t.z).c_str(), ccmap::to_string(status));
    print_counters(counters);
  }

  void query(int layer, float x, float y) const {
    const ccmap::QueryResult q = layer < 0 ? stack_->query(x, y) : stack_->query_layer(layer, x, y);
    std::printf("query %d %s %s status=%s layer=%d cell_width_m=%s height_m=%s slope_x=%s slope_y=%s inclination=%s"
                " normal_variance_m2=%s elevation_variance_m2=%s weight=%s class=%s upset=%d\n",
                layer, bits(x).c_str(), bits(y).c_str(), ccmap::to_string(q.status), q.layer,
                bits(q.cell_width_m).c_str(), bits(q.height_m).c_str(), bits(q.slope_x).c_str(),
                bits(q.slope_y).c_str(), bits(q.inclination).c_str(), bits(q.normal_variance).c_str(),
                bits(q.elevation_variance).c_str(), bits(q.weight).c_str(), ccmap::to_string(q.cell_class), q.upset ? 1 : 0);
  }

  /// A single-event upset in every `stride`-th live finest cell (one bit in the middle of the
  /// cell's bytes, flipped in place as radiation would), then the scrub's empty frames, which
  /// find and distrust them. The distrust survives the snapshot finish() writes.
  void upset(std::size_t stride, PointXYZ origin) {
    const auto& fine = ccmap::detail::PlannerAccess<Config>::view(*stack_).layers().fine_storage;
    auto* base = reinterpret_cast<unsigned char*>(stack_.get());
    std::size_t live = 0;
    std::size_t flipped = 0;
    for (const auto& c : fine) {
      if (!(c.weight > 0.0F) || live++ % stride != 0U) continue;
      const std::size_t at = static_cast<std::size_t>(reinterpret_cast<const unsigned char*>(&c) - base) + sizeof c / 2U;
      base[at] = static_cast<unsigned char>(base[at] ^ 0x04U);
      ++flipped;
    }
    const std::uint32_t scrub = ccmap::detail::ConfigScrubFrames<Config>::value;
    for (std::uint32_t f = 0; f < scrub; ++f) {
      if (stack_->update_frame(nullptr, nullptr, 0U, origin, nullptr) != Status::kOk) {
        std::fprintf(stderr, "%s: a scrub frame was refused\n", name_.c_str());
        std::exit(1);
      }
    }
    std::printf("upset %zu %u\n", flipped, scrub);
  }

  /// Stack queries on a grid over [x0, x1] x [y0, y1] (steps chosen not to align with cells),
  /// then every layer's own answer on a coarser grid.
  void queries(float x0, float x1, float y0, float y1) const {
    for (float y = y0; y <= y1; y += 0.173F) {
      for (float x = x0; x <= x1; x += 0.137F) query(-1, x, y);
    }
    for (int layer = 0; layer < StackType::kLayerCount; ++layer) {
      for (float y = y0; y <= y1; y += 0.61F) {
        for (float x = x0; x <= x1; x += 0.53F) query(layer, x, y);
      }
    }
    query(-1, 500.0F, 0.0F);       // outside every window
    query(-1, std::nanf(""), 0.0F);  // not a position
  }

  void finish(const char* snapshot_dir) const {
    for (int layer = 0; layer < StackType::kLayerCount; ++layer) {
      std::vector<ccmap::CellRecord> cells(StackType::layer_capacity(layer));
      std::size_t written = 0;
      if (stack_->export_layer(layer, cells.data(), cells.size(), &written) != Status::kOk) std::exit(1);
      const ccmap::CellIndex centre = stack_->layer_centre(layer);
      std::printf("layer %d %zu %d %d %d %s %s\n", layer, written, StackType::layer_side(layer), centre.x, centre.y,
                  bits(stack_->layer_cell_width(layer)).c_str(), bits(stack_->normal_variance_threshold(layer)).c_str());
      for (std::size_t i = 0; i < written; ++i) {
        const ccmap::CellRecord& r = cells[i];
        std::printf("%d %d %s %s %s %s %s %s %s %s %s\n", r.index.x, r.index.y, bits(r.centre_x).c_str(),
                    bits(r.centre_y).c_str(), bits(r.weight).c_str(), bits(r.height_m).c_str(), bits(r.slope_x).c_str(),
                    bits(r.slope_y).c_str(), bits(r.normal_variance).c_str(), bits(r.elevation_variance).c_str(),
                    ccmap::to_string(r.cell_class));
      }
    }
    std::printf("totals");
    print_counters(stack_->total_counters());
    std::printf("rejected %u %u\n", stack_->rejected_moves(), stack_->rejected_frames());
    if (snapshot_dir != nullptr) {
      const std::string path = std::string(snapshot_dir) + "/" + name_ + ".ccms";
      std::vector<std::uint8_t> bytes(ccmap::snapshot_size<Config>());
      std::size_t written = 0;
      std::FILE* out = std::fopen(path.c_str(), "wb");
      if (ccmap::save_snapshot(*stack_, bytes.data(), bytes.size(), &written) != Status::kOk || out == nullptr ||
          std::fwrite(bytes.data(), 1, written, out) != written || std::fclose(out) != 0) {
        std::fprintf(stderr, "cannot write %s\n", path.c_str());
        std::exit(1);
      }
      std::printf("snapshot %s\n", path.c_str());
    }
    std::printf("end\n");
  }

 private:
  static ccmap::Pose pose(const float (&r)[3][3], PointXYZ t) {
    ccmap::Pose p{};
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) p.rotation[i][j] = r[i][j];
    }
    p.translation = PointXYZ{t.x, t.y, t.z};
    return p;
  }

  std::string name_;
  std::unique_ptr<StackType> stack_ = std::make_unique<StackType>();
};

const float kNan = std::nanf("");

void cadre_stereo(const char* dir) {
  // The library's defaults: CADRE stereo, 4 cm Kalman + 8..64 cm CCM.
  Scenario<ccmap::CadreConfig> s("cadre_stereo", "cadre", ccmap::default_stack_params(0.04F));
  s.move(0.0F, 0.0F);
  s.frame(make_frame(10U, 4000, 0.2, 4.6, -2.0, 2.0, false), PointXYZ{0.0F, 0.0F, 0.175F});
  s.move(kNan, 0.0F);                                                      // refused
  s.frame(make_frame(20U, 10, 0.2, 1.0, -1.0, 1.0, false), PointXYZ{0.0F, kNan, 0.175F});  // refused
  s.move(0.9F, 0.3F);
  s.frame(make_frame(30U, 4000, 1.0, 7.0, -1.7, 2.3, false), PointXYZ{0.9F, 0.3F, 0.175F});
  s.sensor_frame(make_frame(40U, 3000, 1.5, 4.5, -1.0, 1.8, false), 0.35, PointXYZ{1.2F, 0.4F, 0.175F});
  s.queries(-0.5F, 5.0F, -2.2F, 2.6F);
  s.finish(dir);
}

void cadre_upset(const char* dir) {
  // cadre_stereo's first frame, then upsets in one live finest cell of seven: the answers the
  // snapshot carries to a ground tool (Python reads it with Map.load).
  Scenario<ccmap::CadreConfig> s("cadre_upset", "cadre", ccmap::default_stack_params(0.04F));
  s.frame(make_frame(10U, 4000, 0.2, 4.6, -2.0, 2.0, false), PointXYZ{0.0F, 0.0F, 0.175F});
  s.frame(make_frame(15U, 4000, 0.2, 3.0, -1.5, 1.5, false), PointXYZ{0.0F, 0.0F, 0.175F});
  s.upset(7U, PointXYZ{0.0F, 0.0F, 0.175F});
  s.queries(-0.5F, 3.0F, -1.6F, 1.6F);
  s.finish(dir);
}

void ccm_lidar(const char* dir) {
  ccmap::StackParams p = ccmap::default_stack_params(0.16F);
  p.noise = ccmap::sensor::NoiseModel::lidar(ccmap::sensor::LidarParams{0.01F, 0.0F});
  p.weight_limit = 200.0F;
  p.coverage_tau = 0.7F;
  p.min_weight = 3.0F;
  p.obstacle_fraction = 0.5F;
  p.max_inclination = 0.5F;
  p.normal_variance_threshold[0] = 0.0004F;
  Scenario<ccmap::SingleCcmConfig> s("ccm_lidar", "ccm cell_width=" + bits(0.16F) + " sensor=@lidar lidar_sigma_m=" +
                                                      bits(0.01F) + " weight_limit=" + bits(200.0F) + " coverage_tau=" +
                                                      bits(0.7F) + " min_weight=" + bits(3.0F) + " obstacle_fraction=" +
                                                      bits(0.5F) + " max_inclination=" + bits(0.5F) +
                                                      " normal_variance_threshold=[" + bits(0.0004F) + "]",
                                     p);
  s.move(1.0F, -0.5F);
  s.frame(make_frame(50U, 2000, -12.0, 16.0, -14.0, 12.0, true), PointXYZ{1.0F, -0.5F, 1.5F});  // sparse, wide
  s.frame(make_frame(60U, 8000, -3.0, 5.0, -3.0, 4.0, true), PointXYZ{2.0F, 0.0F, 1.5F});
  s.move(3.3F, 1.1F);
  s.frame(make_frame(70U, 8000, -2.0, 6.0, -2.0, 5.0, false), PointXYZ{3.3F, 1.1F, 1.5F});
  s.queries(-4.0F, 7.0F, -4.0F, 6.0F);
  s.finish(dir);
}

void kf_stereo(const char* dir) {
  ccmap::StackParams p = ccmap::default_stack_params(0.08F);
  p.kalman_min_variance = 1.0e-6F;
  Scenario<ccmap::SingleKalmanConfig> s("kf_stereo", "kf kalman_min_variance=" + bits(1.0e-6F), p);
  s.frame(make_frame(80U, 4000, 0.1, 2.4, -1.5, 1.5, false), PointXYZ{0.0F, 0.0F, 0.175F});
  s.move(0.5F, 0.0F);
  s.sensor_frame(make_frame(90U, 4000, 0.4, 2.2, -1.0, 1.0, false), -0.2, PointXYZ{0.5F, 0.1F, 0.2F});
  s.queries(-0.5F, 2.5F, -1.6F, 1.6F);
  s.finish(dir);
}

void omg_inverse_variance(const char* dir) {
  ccmap::StackParams p = ccmap::default_stack_params(0.05F);
  p.noise = ccmap::sensor::NoiseModel::stereo(ccmap::sensor::StereoParams{800.0F, 0.1F, 0.2F});
  p.noise.set_weight_mode(ccmap::sensor::WeightMode::kInverseVariance, 1.5F);
  p.weight_limit = 50.0F;
  Scenario<ccmap::SingleOmgConfig> s("omg_inverse_variance",
                                     "omg cell_width=" + bits(0.05F) + " focal_px=" + bits(800.0F) + " baseline_m=" +
                                         bits(0.1F) + " disparity_sigma_px=" + bits(0.2F) +
                                         " weight_mode=@inverse_variance reference_range_m=" + bits(1.5F) +
                                         " weight_limit=" + bits(50.0F),
                                     p);
  s.move(0.2F, 0.1F);
  s.frame(make_frame(100U, 4000, 0.1, 2.2, -1.2, 1.2, true), PointXYZ{0.0F, 0.0F, 0.3F});
  s.frame(make_frame(110U, 4000, 0.3, 2.4, -0.8, 1.6, false), PointXYZ{0.3F, 0.5F, 0.3F});
  s.queries(-0.5F, 3.0F, -1.5F, 2.0F);
  s.finish(dir);
}

}  // namespace

int main(int argc, char** argv) {
  const char* dir = argc > 1 ? argv[1] : nullptr;
  cadre_stereo(dir);
  cadre_upset(dir);
  ccm_lidar(dir);
  kf_stereo(dir);
  omg_inverse_variance(dir);
  return 0;
}
