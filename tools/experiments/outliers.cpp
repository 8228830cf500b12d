#include "experiments/outliers.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>

#include "ccmap/map/stack.hpp"
#include "experiments/common.hpp"
#include "sim/rng.hpp"

namespace ccmap::experiments {

namespace {

/// Height of the ground (m) at (x, y) in a frame, and whether (x, y) is on it at all.
using Ground = std::function<double(double x, double y)>;

/// One single-layer map of any kind behind a small interface.
class Map {
 public:
  virtual ~Map() = default;
  virtual void frame(const std::vector<PointXYZ>& pts, PointXYZ origin, FrameCounters* c) = 0;
  virtual QueryResult query(double x, double y) const = 0;
  virtual float width() const = 0;
  /// Height at each cell's centre (CellRecord), known or not; NaN where nothing was seen.
  virtual std::vector<double> centre_heights(const std::vector<std::pair<double, double>>& centres) const = 0;
};

template <typename Config>
class StackMap final : public Map {
 public:
  StackMap(double width, double noise_m, const GateSetting* gate) {
    StackParams p = default_stack_params(static_cast<float>(width));
    p.noise = sensor::NoiseModel::lidar(sensor::LidarParams{static_cast<float>(noise_m), 0.0F});
    if (gate != nullptr) {
      gate->apply(&p);
    } else {
      p.outlier_gate_sigma = 0.0F;
    }
    ok_ = stack_->init(p) == Status::kOk && stack_->move_to(0.0F, 0.0F) == Status::kOk;
  }
  bool ok() const { return ok_; }
  void frame(const std::vector<PointXYZ>& pts, PointXYZ origin, FrameCounters* c) override {
    FrameCounters f{};
    (void)stack_->update_frame(pts.data(), pts.size(), origin, &f);
    detail::accumulate(*c, f);
  }
  QueryResult query(double x, double y) const override {
    return stack_->query_layer(0, static_cast<float>(x), static_cast<float>(y));
  }
  float width() const override { return stack_->layer_cell_width(0); }
  std::vector<double> centre_heights(const std::vector<std::pair<double, double>>& centres) const override {
    std::vector<CellRecord> records(Stack<Config>::layer_capacity(0));
    std::size_t written = 0;
    std::vector<double> out(centres.size(), std::nan(""));
    if (stack_->export_layer(0, records.data(), records.size(), &written) != Status::kOk) return out;
    const float w = width();
    for (std::size_t i = 0; i < written; ++i) {
      for (std::size_t k = 0; k < centres.size(); ++k) {
        if (std::fabs(records[i].centre_x - centres[k].first) < 0.25 * w &&
            std::fabs(records[i].centre_y - centres[k].second) < 0.25 * w) {
          out[k] = records[i].height_m;
        }
      }
    }
    return out;
  }

 private:
  std::unique_ptr<Stack<Config>> stack_ = std::make_unique<Stack<Config>>();
  bool ok_ = false;
};

/// gate nullptr: the gate off.
std::unique_ptr<Map> make_map(const std::string& kind, double width, double noise_m, const GateSetting* gate) {
  if (kind == "CCM") return std::make_unique<StackMap<SingleCcmConfig>>(width, noise_m, gate);
  if (kind == "Kalman") return std::make_unique<StackMap<SingleKalmanConfig>>(width, noise_m, gate);
  return std::make_unique<StackMap<SingleOmgConfig>>(width, noise_m, gate);
}

/// A frame of n points uniform over the square [-a/2, a/2)^2 (or over `region` if given) on
/// `ground`, Gaussian height noise, `outlier_share` of them 0.2 .. 1 m up.
std::vector<PointXYZ> make_frame(const OutlierConfig& cfg, sim::Rng& rng, int n, const Ground& ground,
                                 double outlier_share) {
  std::vector<PointXYZ> pts;
  pts.reserve(static_cast<std::size_t>(n));
  const double h = 0.5 * cfg.area_m;
  for (int i = 0; i < n; ++i) {
    const double x = rng.uniform(-h, h), y = rng.uniform(-h, h);
    double z = ground(x, y) + cfg.noise_m * rng.normal();
    if (rng.uniform() < outlier_share) z += rng.uniform(0.2, 1.0);
    pts.push_back(PointXYZ{static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)});
  }
  return pts;
}

PointXYZ sensor(const OutlierConfig& cfg) { return PointXYZ{0.0F, 0.0F, static_cast<float>(cfg.sensor_height_m)}; }

SlopeRow run_slope(const OutlierConfig& cfg, double w, const std::string& kind, bool outliers, bool gate) {
  SlopeRow row;
  row.cell_width_m = w;
  row.map = kind;
  row.variant = outliers ? "outliers" : "clean";
  row.gate = gate;
  auto map = make_map(kind, w, cfg.noise_m, gate ? &cfg.gate : nullptr);
  sim::Rng rng(sim::hash_combine(cfg.seed, 0x51, static_cast<std::uint64_t>(w * 1e6)));
  const Ground plane = [&](double x, double) { return cfg.slope * x; };
  FrameCounters c{};
  for (int f = 0; f < cfg.frames; ++f) {
    map->frame(make_frame(cfg, rng, cfg.points_per_frame, plane, outliers ? cfg.outlier_share : 0.0), sensor(cfg), &c);
  }
  double sum_sq = 0.0;
  std::size_t known = 0, total = 0;
  const double lo = -0.5 * cfg.area_m + w, hi = 0.5 * cfg.area_m - w;
  for (double y = lo; y < hi; y += cfg.query_step_m) {
    for (double x = lo; x < hi; x += cfg.query_step_m) {
      ++total;
      const QueryResult q = map->query(x, y);
      if (q.status != Status::kOk) continue;
      const double e = q.height_m - plane(x, y);
      sum_sq += e * e;
      ++known;
    }
  }
  row.rms_m = known > 0 ? std::sqrt(sum_sq / static_cast<double>(known)) : 0.0;
  row.known_share = total > 0 ? static_cast<double>(known) / static_cast<double>(total) : 0.0;
  row.held = c.gated_held;
  row.admitted = c.gated_admitted;
  row.dropped = c.gated_dropped;
  return row;
}

/// Frames after the change until done() holds (checked after each frame), or -1.
int frames_until(const OutlierConfig& cfg, Map& map, sim::Rng& rng, int points, const Ground& after,
                 const std::function<bool()>& done) {
  FrameCounters c{};
  for (int f = 1; f <= cfg.change_frames; ++f) {
    map.frame(make_frame(cfg, rng, points, after, 0.0), sensor(cfg), &c);
    if (done()) return f;
  }
  return -1;
}

/// Cell centres wholly inside [lo, hi)^2 for cells of width w.
std::vector<std::pair<double, double>> centres_inside(double lo, double hi, double w) {
  std::vector<std::pair<double, double>> out;
  for (double y = std::ceil(lo / w) * w; y + w <= hi + 1e-9; y += w) {
    for (double x = std::ceil(lo / w) * w; x + w <= hi + 1e-9; x += w) out.emplace_back(x + 0.5 * w, y + 0.5 * w);
  }
  return out;
}

/// True if at least 90 % of the cells at these centres hold a height within `tolerance` of
/// `height` at their centre (known or not: a sparsely seen cell may lack the points or the
/// coverage to be known).
bool all_near(const Map& map, const std::vector<std::pair<double, double>>& centres, double height, double tolerance) {
  std::size_t near = 0;
  for (const double h : map.centre_heights(centres)) near += std::fabs(h - height) <= tolerance ? 1U : 0U;
  return 10U * near >= 9U * centres.size();
}

ChangeRow run_change(const OutlierConfig& cfg, double w, const std::string& kind, const std::string& change,
                     bool sparse, bool gate) {
  ChangeRow row;
  row.cell_width_m = w;
  row.change = kind + " " + change;
  row.sparse = sparse;
  row.gate = gate;
  auto map = make_map(kind, w, cfg.noise_m, gate ? &cfg.gate : nullptr);
  sim::Rng rng(sim::hash_combine(cfg.seed, 0xC4, static_cast<std::uint64_t>(w * 1e6)));
  const double cells = (cfg.area_m / w) * (cfg.area_m / w);
  const int points = sparse ? static_cast<int>(cells) : cfg.points_per_frame;
  const Ground flat = [](double, double) { return 0.0; };
  FrameCounters c{};
  if (change == "seeded") {
    // Five outliers alone in one cell, then the ground all around it.
    const double cx = (std::floor(1.0 / w) + 0.5) * w, cy = (std::floor(1.0 / w) + 0.5) * w;
    std::vector<PointXYZ> seed;
    for (int i = 0; i < 5; ++i) {
      seed.push_back(PointXYZ{static_cast<float>(cx + 0.2 * w * (i % 3 - 1)), static_cast<float>(cy + 0.2 * w * (i / 3)),
                              static_cast<float>(0.5 + 0.01 * i)});
    }
    map->frame(seed, sensor(cfg), &c);
    const std::vector<std::pair<double, double>> cell = {{cx, cy}};
    row.frames = frames_until(cfg, *map, rng, points, flat, [&] { return all_near(*map, cell, 0.0, 0.01); });
    return row;
  }
  for (int f = 0; f < cfg.frames; ++f) map->frame(make_frame(cfg, rng, points, flat, 0.0), sensor(cfg), &c);
  if (change == "box") {
    const double lo = 0.5, hi = 0.5 + cfg.box_size_m;
    const Ground box = [&](double x, double y) { return (x >= lo && x < hi && y >= lo && y < hi) ? cfg.box_height_m : 0.0; };
    const auto top = centres_inside(lo, hi, w);
    row.frames = frames_until(cfg, *map, rng, points, box, [&] { return all_near(*map, top, cfg.box_height_m, 0.01); });
  } else {
    const Ground raised = [](double, double) { return 0.1; };
    const double h = 0.5 * cfg.area_m - w;
    const auto all = centres_inside(-h, h, w);
    row.frames = frames_until(cfg, *map, rng, points, raised, [&] { return all_near(*map, all, 0.1, 0.01); });
  }
  return row;
}

}  // namespace

const SlopeRow* OutlierResult::find(double w, const std::string& map, const std::string& variant, bool gate) const {
  for (const SlopeRow& r : slope) {
    if (std::fabs(r.cell_width_m - w) < 1e-9 && r.map == map && r.variant == variant && r.gate == gate) return &r;
  }
  return nullptr;
}

const ChangeRow* OutlierResult::find_change(double w, const std::string& name, bool sparse, bool gate) const {
  for (const ChangeRow& r : change) {
    if (std::fabs(r.cell_width_m - w) < 1e-9 && r.change == name && r.sparse == sparse && r.gate == gate) return &r;
  }
  return nullptr;
}

OutlierResult run_outliers(const OutlierConfig& cfg) {
  OutlierResult r;
  for (const double w : cfg.cell_widths_m) {
    for (const char* kind : {"CCM", "Kalman", "OMG"}) {
      for (const bool outliers : {false, true}) {
        for (const bool gate : {false, true}) r.slope.push_back(run_slope(cfg, w, kind, outliers, gate));
      }
    }
  }
  for (const double w : cfg.cell_widths_m) {
    for (const char* kind : {"CCM", "Kalman", "OMG"}) {
      for (const char* change : {"box", "seeded", "jump"}) {
        for (const bool sparse : {false, true}) {
          for (const bool gate : {false, true}) r.change.push_back(run_change(cfg, w, kind, change, sparse, gate));
        }
      }
    }
  }
  return r;
}

std::string outlier_tables(const OutlierConfig& cfg, const OutlierResult& r) {
  std::string out = format(
      "Outliers on a %.0f %% slope: %d frames of %d points over %.0f x %.0f m, noise %.1f mm, %.1f %% of the points "
      "0.2-1 m up; RMS of the map height (CCM: sub-cell plane) against the plane over known cells\n",
      100.0 * cfg.slope, cfg.frames, cfg.points_per_frame, cfg.area_m, cfg.area_m, 1000.0 * cfg.noise_m,
      100.0 * cfg.outlier_share);
  Table t({"cell", "map", "clean, gate off", "clean, gate on", "outliers, gate off", "outliers, gate on", "known (on)",
           "held / admitted / dropped (outliers, on)"});
  for (const double w : cfg.cell_widths_m) {
    for (const char* kind : {"CCM", "Kalman", "OMG"}) {
      const SlopeRow* a = r.find(w, kind, "clean", false);
      const SlopeRow* b = r.find(w, kind, "clean", true);
      const SlopeRow* c = r.find(w, kind, "outliers", false);
      const SlopeRow* d = r.find(w, kind, "outliers", true);
      t.add_row({format("%.0f cm", 100.0 * w), kind, format("%.2f mm", 1000.0 * a->rms_m),
                 format("%.2f mm", 1000.0 * b->rms_m), format("%.2f mm", 1000.0 * c->rms_m),
                 format("%.2f mm", 1000.0 * d->rms_m), format("%.1f %%", 100.0 * d->known_share),
                 format("%llu / %llu / %llu", static_cast<unsigned long long>(d->held),
                        static_cast<unsigned long long>(d->admitted), static_cast<unsigned long long>(d->dropped))});
    }
  }
  out += t.str();
  out += format(
      "\nReal change: frames after it until it is in the map (box: cells wholly on a %.0f cm high, %.1f m box "
      "within 1 cm of its top; seeded: a cell first seeded by 5 outliers 0.5 m up within 1 cm of the ground; "
      "jump: every cell within 1 cm of the ground seen 10 cm higher). Dense: %d points per frame; sparse: about "
      "one point per cell and frame. \"never\": not within %d frames\n",
      100.0 * cfg.box_height_m, cfg.box_size_m, cfg.points_per_frame, cfg.change_frames);
  Table c({"cell", "change", "dense, gate off", "dense, gate on", "sparse, gate off", "sparse, gate on"});
  auto cell = [](const ChangeRow* row) { return row->frames < 0 ? std::string("never") : format("%d", row->frames); };
  for (const double w : cfg.cell_widths_m) {
    for (const char* kind : {"CCM", "Kalman", "OMG"}) {
      for (const char* change : {"box", "seeded", "jump"}) {
        const std::string name = std::string(kind) + " " + change;
        c.add_row({format("%.0f cm", 100.0 * w), name, cell(r.find_change(w, name, false, false)),
                   cell(r.find_change(w, name, false, true)), cell(r.find_change(w, name, true, false)),
                   cell(r.find_change(w, name, true, true))});
      }
    }
  }
  out += c.str();
  return out;
}

}  // namespace ccmap::experiments
