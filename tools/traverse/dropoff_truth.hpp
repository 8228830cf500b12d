// An independent reference for drop-offs (issue 31 item 3; docs/evaluation.md, "Ghosts and
// drop-offs", "What any line of sight proves"): which cells of a map's layer some line of sight of
// the frames so far proves to lie a drop below the ground at the rim, computed by brute force in
// double precision from the simulator's true terrain, not from the library's walk or table.
//
// Definition (per layer k of cell width w_k and obstacle step s_k = obstacle_fraction w_k; the
// cells of k's grid, [i w_k, (i + 1) w_k) x [j w_k, (j + 1) w_k) in the map frame, lying wholly
// inside the region):
//  - a line of sight is the segment from the camera centre to the pixel's true terrain point
//    (the ray cast, before noise), shortened at its far end by `shorten_m` (the experiment: three
//    range errors of the map's noise model at the true range, 3 sigma_m(r), as the library shortens
//    its rays; docs/design.md section 12);
//  - its rim ground g is given with it (the experiment: the highest true terrain height under its
//    horizontal path within 0.1 m of the obstacle's near rim line x = rim_x);
//  - over a cell, the line of sight's lowest height is the lower of its heights where its
//    horizontal path enters and leaves the cell's square (it is straight): `below` of the cell is
//    the least over every line of sight crossing the square of (that lowest height - g);
//  - a cell is hidden when no true terrain point of any pixel lands in its square;
//  - a cell is provably a drop when it is hidden and below < -s_k.
// Host tool code: heap, double.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "ccmap/map/types.hpp"
#include "sim/stereo.hpp"
#include "sim/terrain.hpp"

namespace ccmap::traverse {

/// The reference over an axis-aligned region, for a list of layers (cell width and step each).
class DropoffTruth {
 public:
  struct Layer {
    double width_m = 0.0, step_m = 0.0;
    std::int64_t i0 = 0, j0 = 0;  ///< the first cell wholly inside the region
    int ni = 0, nj = 0;           ///< cells wholly inside, per axis
    std::vector<char> hit;        ///< a true point landed in the cell
    std::vector<double> below;    ///< least (lowest height over the cell - rim ground); +inf: no ray
  };

  DropoffTruth(double x0, double x1, double y0, double y1, const std::vector<double>& widths_m,
               const std::vector<double>& steps_m);

  /// A pixel's true terrain point (map frame).
  void add_point(double x, double y);
  /// A line of sight from `from` to `to` (already shortened), with its rim ground height.
  void add_ray(const sim::Point3& from, const sim::Point3& to, double rim_ground_m);

  int layer_count() const { return static_cast<int>(layers_.size()); }
  const Layer& layer(int k) const { return layers_[static_cast<std::size_t>(k)]; }
  bool hidden(int k, int i, int j) const { return layer(k).hit[index(k, i, j)] == 0; }
  double below(int k, int i, int j) const { return layer(k).below[index(k, i, j)]; }
  /// Hidden and a line of sight passed over it more than the layer's step below its rim ground.
  bool provable(int k, int i, int j) const { return hidden(k, i, j) && below(k, i, j) < -layer(k).step_m; }
  double centre_x(int k, int i) const { return (static_cast<double>(layer(k).i0 + i) + 0.5) * layer(k).width_m; }
  double centre_y(int k, int j) const { return (static_cast<double>(layer(k).j0 + j) + 0.5) * layer(k).width_m; }

 private:
  std::size_t index(int k, int i, int j) const {
    return static_cast<std::size_t>(j) * static_cast<std::size_t>(layer(k).ni) + static_cast<std::size_t>(i);
  }
  double x0_, x1_, y0_, y1_;
  std::vector<Layer> layers_;
};

/// The highest true terrain height under the horizontal path from `from` to `to` within 0.1 m of
/// the line x = rim_x (sampled every 5 mm, both ends of that stretch included); NaN if the path
/// does not reach that stretch.
double rim_ground(const sim::HeightRaster& raster, const sim::Point3& from, const sim::Point3& to, double rim_x);

/// Feeds one simulated frame: every pixel's true point, and its line of sight shortened by
/// `sigmas` range errors of `sigma_at_range` (a callable double(range_m)) at its true range.
template <typename SigmaFn>
void add_frame(DropoffTruth& truth, const sim::StereoCamera& camera, const sim::StereoFrame& frame,
               const sim::HeightRaster& raster, double rim_x, double sigmas, SigmaFn&& sigma_at_range) {
  const sim::Point3 o = frame.sensor_position_true;
  for (std::size_t n = 0; n < frame.points_sensor.size() && n < frame.pixels.size(); ++n) {
    const sim::PixelSample& px = frame.pixels[n];
    const double z = px.true_depth_m, measured = px.depth_m;
    if (!(z > 0.0) || !(measured > 0.0) || px.streak || px.mismatch) continue;
    const sim::Point3& s = frame.points_sensor[n];
    const double k = z / measured;  // the pinhole's point scales with its depth along the pixel's ray
    const sim::Point3 p = camera.sensor_to_world(sim::Point3{s.x * k, s.y * k, s.z * k}, o, frame.true_pose.yaw);
    truth.add_point(p.x, p.y);
    const double r = std::sqrt((p.x - o.x) * (p.x - o.x) + (p.y - o.y) * (p.y - o.y) + (p.z - o.z) * (p.z - o.z));
    const double m = sigmas * sigma_at_range(r);
    if (!(m < r)) continue;
    const double f = 1.0 - m / r;
    const sim::Point3 e{o.x + f * (p.x - o.x), o.y + f * (p.y - o.y), o.z + f * (p.z - o.z)};
    const double g = rim_ground(raster, o, e, rim_x);
    if (std::isfinite(g)) truth.add_ray(o, e, g);
  }
}

/// One evaluation of a map against the reference: the cells of each layer that are the map's walk
/// layer there (the finest layer whose window holds the cell's centre), and what the stack query
/// answers at their centres.
struct DropTruthRow {
  double range_m = 0.0;     ///< camera to the near rim
  int hidden = 0;           ///< hidden cells (of the walk layers)
  int provable = 0;         ///< of them provably a drop
  int answered = 0;         ///< of those the stack query answers drop-off
  int drop_not_provable = 0;  ///< cells the query answers drop-off that the reference does not prove
  int not_provable_deep = 0;  ///< of those, cells whose true terrain lies wholly a step below the rim ground
  int not_provable_seen = 0;  ///< of those, cells a true point landed in (not hidden)
  int provable_by_layer[4] = {0, 0, 0, 0}, answered_by_layer[4] = {0, 0, 0, 0};
};

/// True if the true terrain over the square [x0, x0 + w) x [y0, y0 + w) (sampled every 1 cm)
/// lies wholly more than `step_m` below the rim ground on its row (the highest terrain within
/// 0.1 m of x = rim_x at the square's centre y): the cell is a drop, proved by a ray or not.
bool truly_deep(const sim::HeightRaster& raster, double rim_x, double x0, double y0, double w, double step_m);

template <typename Map>
DropTruthRow evaluate_drops(const DropoffTruth& truth, const Map& map, double range_m, const sim::HeightRaster& raster,
                            double rim_x) {
  DropTruthRow row;
  row.range_m = range_m;
  for (int k = 0; k < truth.layer_count(); ++k) {
    const DropoffTruth::Layer& l = truth.layer(k);
    for (int j = 0; j < l.nj; ++j) {
      for (int i = 0; i < l.ni; ++i) {
        const float cx = static_cast<float>(truth.centre_x(k, i)), cy = static_cast<float>(truth.centre_y(k, j));
        int walk = -1;
        for (int q = 0; q <= k && walk < 0; ++q) {
          if (map.query_layer(q, cx, cy).status != Status::kOutsideMap) walk = q;
        }
        if (walk != k) continue;
        const bool drop = map.query(cx, cy).cell_class == CellClass::kDropOff;
        if (truth.hidden(k, i, j)) ++row.hidden;
        if (truth.provable(k, i, j)) {
          ++row.provable;
          if (k < 4) ++row.provable_by_layer[k];
          if (drop) {
            ++row.answered;
            if (k < 4) ++row.answered_by_layer[k];
          }
        } else if (drop) {
          ++row.drop_not_provable;
          if (!truth.hidden(k, i, j)) ++row.not_provable_seen;
          const double w = l.width_m;
          if (truly_deep(raster, rim_x, truth.centre_x(k, i) - 0.5 * w, truth.centre_y(k, j) - 0.5 * w, w, l.step_m)) {
            ++row.not_provable_deep;
          }
        }
      }
    }
  }
  return row;
}

/// The reference over the rover's swath (0.6 m wide about the line y) from x0 to x1, for the
/// map's layers up to 32 cm (step obstacle_fraction w each).
template <typename Map>
std::unique_ptr<DropoffTruth> make_swath_truth(const Map& map, double x0, double x1, double y) {
  std::vector<double> widths, steps;
  for (int k = 0; k < Map::kLayerCount && k < 4; ++k) {
    widths.push_back(double{map.layer_cell_width(k)});
    steps.push_back(double{map.params().obstacle_fraction} * double{map.layer_cell_width(k)});
  }
  return std::make_unique<DropoffTruth>(x0, x1, y - 0.3, y + 0.3, widths, steps);
}

/// A progress line: one frame's row.
void log_truth_row(std::FILE* log, const std::string& name, const DropTruthRow& row);

struct DropCase;
/// The table of docs/evaluation.md ("What any line of sight proves") from the cases' rows.
std::string drop_truth_report(const std::vector<DropCase>& cases);

}  // namespace ccmap::traverse
