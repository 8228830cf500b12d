#include "traverse/ghost_truth.hpp"

#include <algorithm>
#include <limits>

#include "experiments/common.hpp"

namespace ccmap::traverse {

bool passes_clearly_below(const TruthCell& cell, const SightLine& line) {
  // The segment origin + s (hit - origin), s in [0, 1], clipped to the square (slab method).
  const double d[2] = {line.hx - line.ox, line.hy - line.oy};
  const double o[2] = {line.ox, line.oy};
  const double lo[2] = {cell.x0, cell.y0};
  double s_in = 0.0, s_out = 1.0;
  for (int a = 0; a < 2; ++a) {
    if (d[a] == 0.0) {
      if (o[a] < lo[a] || o[a] > lo[a] + cell.w) return false;
      continue;
    }
    double s0 = (lo[a] - o[a]) / d[a], s1 = (lo[a] + cell.w - o[a]) / d[a];
    if (s0 > s1) std::swap(s0, s1);
    s_in = std::max(s_in, s0);
    s_out = std::min(s_out, s1);
  }
  // Crosses the square, and its true point lies beyond it (not in it, not before it).
  if (!(s_in < s_out) || !(s_out < 1.0)) return false;
  const double dz = line.hz - line.oz;
  const double z_high = line.oz + std::max(s_in * dz, s_out * dz);
  return z_high < cell.top - cell.margin;
}

int lines_clearly_below(const TruthCell& cell, const std::vector<SightLine>& lines) {
  int n = 0;
  for (const SightLine& l : lines) n += passes_clearly_below(cell, l) ? 1 : 0;
  return n;
}

std::vector<SightLine> sight_lines(const sim::StereoCamera& camera, const sim::DepthImage& depth,
                                   const sim::Point3& camera_centre, double yaw) {
  std::vector<SightLine> out;
  const sim::StereoParams& p = camera.params();
  const double cx = 0.5 * p.width_px, cy = 0.5 * p.height_px;
  for (int r = 0; r < depth.rows; ++r) {
    const double yn = (r * depth.stride + 0.5 - cy) / p.focal_px;
    for (int c = 0; c < depth.cols; ++c) {
      const float z = depth.at(c, r);
      if (!std::isfinite(z)) continue;
      const double xn = (c * depth.stride + 0.5 - cx) / p.focal_px;
      const sim::Point3 h = camera.sensor_to_world(sim::Point3{xn * z, yn * z, double{z}}, camera_centre, yaw);
      out.push_back(SightLine{camera_centre.x, camera_centre.y, camera_centre.z, h.x, h.y, h.z});
    }
  }
  return out;
}

GhostTruth::GhostTruth(const sim::HeightRaster& ground, double obstacle_fraction, int min_rays,
                       std::function<bool(double, double, double)> rock_in,
                       std::function<bool(double, double, int)> mate_at, std::function<bool(double, double, int)> rover_at)
    : ground_(ground),
      obstacle_fraction_(obstacle_fraction),
      rock_in_(std::move(rock_in)),
      mate_at_(std::move(mate_at)),
      rover_at_(std::move(rover_at)) {
  result_.min_rays = min_rays;
}

GhostTruth::CellFacts& GhostTruth::facts(const MapCellView& c) {
  const Key key{c.layer, c.ix, c.iy};
  auto it = facts_.find(key);
  if (it != facts_.end()) return it->second;
  CellFacts f;
  // The lowest raster vertex that bilinear interpolation inside the square can use (the square
  // grown by one raster step): no point of the true terrain in the cell lies lower.
  const double res = ground_.resolution();
  const double x0 = c.ix * c.w, y0 = c.iy * c.w;
  const int i0 = std::max(0, static_cast<int>(std::floor((x0 - ground_.origin_x()) / res)));
  const int i1 = std::min(ground_.nx() - 1, static_cast<int>(std::ceil((x0 + c.w - ground_.origin_x()) / res)));
  const int j0 = std::max(0, static_cast<int>(std::floor((y0 - ground_.origin_y()) / res)));
  const int j1 = std::min(ground_.ny() - 1, static_cast<int>(std::ceil((y0 + c.w - ground_.origin_y()) / res)));
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (int j = j0; j <= j1; ++j) {
    for (int i = i0; i <= i1; ++i) {
      lo = std::min(lo, double{ground_.at(i, j)});
      hi = std::max(hi, double{ground_.at(i, j)});
    }
  }
  f.ground_min = lo;
  f.ground_max = hi;
  f.rock = rock_in_((c.ix + 0.5) * c.w, (c.iy + 0.5) * c.w, c.w);
  return facts_.emplace(key, f).first->second;
}

bool GhostTruth::covered_at(const MapCellView& c, int f, const std::function<bool(double, double, int)>& at) const {
  // Sample points 2 cm apart (at least 3 a side) over the square, edges included.
  const int n = std::max(3, static_cast<int>(std::ceil(c.w / 0.02)) + 1);
  const double x0 = c.ix * c.w, y0 = c.iy * c.w;
  for (int b = 0; b < n; ++b) {
    for (int a = 0; a < n; ++a) {
      if (at(x0 + c.w * a / (n - 1), y0 + c.w * b / (n - 1), f)) return true;
    }
  }
  return false;
}

int GhostTruth::first_cover(const MapCellView& c, int upto, const std::function<bool(double, double, int)>& at,
                            int* checked, int* first) const {
  for (int f = *checked + 1; f <= upto && *first < 0; ++f) {
    if (covered_at(c, f, at)) *first = f;
    *checked = f;
  }
  if (*first >= 0) *checked = upto;
  return *first;
}

namespace {

TruthTrack new_track(const MapCellView& c, int f, bool ghost) {
  TruthTrack t;
  t.layer = c.layer;
  t.cx = (c.ix + 0.5) * c.w;
  t.cy = (c.iy + 0.5) * c.w;
  t.w = c.w;
  t.ghost = ghost;
  t.first_frame = f;
  return t;
}

}  // namespace

void GhostTruth::before_update(int f, const std::vector<MapCellView>& cells, const std::vector<SightLine>& lines,
                               double cam_x, double cam_y) {
  result_.frames = f + 1;
  result_.lines += lines.size();
  std::map<Key, bool> present;
  for (const MapCellView& c : cells) {
    const Key key{c.layer, c.ix, c.iy};
    present[key] = true;
    const double margin = obstacle_fraction_ * c.w;
    CellFacts& facts_of = facts(c);
    auto open = open_.find(key);
    if (open == open_.end()) {
      if (!(c.top - margin > facts_of.ground_min)) {
        // No true line of sight can pass below it. A raised ghost surface all the same?
        if (!facts_of.within_margin_noted && c.top > facts_of.ground_max + kRaisedM && f > 0 &&
            !covered_at(c, f, rover_at_) &&
            first_cover(c, f - 1, mate_at_, &facts_of.mate_checked, &facts_of.first_mate) >= 0) {
          facts_of.within_margin_noted = true;
          TruthTrack t = new_track(c, f, true);
          t.seen_range_m = std::hypot(t.cx - cam_x, t.cy - cam_y);
          result_.within_margin.push_back(t);
        }
        continue;
      }
      if (facts_of.mate_checked == std::numeric_limits<int>::max()) continue;  // its one episode is over
      // A rover on it now: its body, not a ghost, and no line reaches past it.
      if (covered_at(c, f, rover_at_)) continue;
      const bool ghost = f > 0 && first_cover(c, f - 1, mate_at_, &facts_of.mate_checked, &facts_of.first_mate) >= 0;
      const bool real = !ghost && first_cover(c, f, rover_at_, &facts_of.rover_checked, &facts_of.first_rover) < 0;
      if (!ghost && !real) continue;  // the map's own past footprint: neither
      TruthTrack t = new_track(c, f, ghost);
      t.rock = facts_of.rock;
      result_.tracks.push_back(t);
      open = open_.emplace(key, result_.tracks.size() - 1).first;
    }
    TruthTrack& t = result_.tracks[open->second];
    if (!(c.top - margin > facts_of.ground_min)) {
      t.sunk = f;
      facts_of.mate_checked = std::numeric_limits<int>::max();
      open_.erase(open);
      continue;
    }
    if (covered_at(c, f, rover_at_)) {
      // A rover over it now: a ghost is not judged this frame; a real cell's track ends (the
      // cell may become a ghost of that rover, tracked afresh once it has left).
      if (!t.ghost) {
        t.ended = f;
        open_.erase(open);
      }
      continue;
    }
    const int n = lines_clearly_below(TruthCell{c.ix * c.w, c.iy * c.w, c.w, c.top, margin}, lines);
    t.max_rays = std::max(t.max_rays, n);
    if (n >= result_.min_rays) {
      ++t.seen_frames;
      if (t.first_seen < 0) {
        t.first_seen = f;
        t.seen_range_m = std::hypot(t.cx - cam_x, t.cy - cam_y);
      }
    }
  }
  // A tracked cell the move took out of the window (or emptied otherwise) ends here.
  for (auto it = open_.begin(); it != open_.end();) {
    if (present.count(it->first) == 0) {
      result_.tracks[it->second].ended = f;
      facts_[it->first].mate_checked = std::numeric_limits<int>::max();
      it = open_.erase(it);
    } else {
      ++it;
    }
  }
}

void GhostTruth::after_update(int f, const std::vector<MapCellView>& cells) {
  std::map<Key, bool> present;
  for (const MapCellView& c : cells) present[Key{c.layer, c.ix, c.iy}] = true;
  for (auto it = open_.begin(); it != open_.end();) {
    if (present.count(it->first) == 0) {
      TruthTrack& t = result_.tracks[it->second];
      t.emptied = f;
      t.seen_until_emptied = t.seen_frames;
      facts_[it->first].mate_checked = std::numeric_limits<int>::max();  // one episode per cell
      it = open_.erase(it);
    } else {
      ++it;
    }
  }
}

std::string ghost_truth_report(const GhostTruthResult& r) {
  using experiments::format;
  std::string s = format(
      "Reference for issue 31 item 2 (rover 1's map, %d frames, %llu true lines of sight): a cell is seen clearly\n"
      "below its surface in a frame when >= %d lines of sight cross it below its top less the clear margin and\n"
      "reach true ground beyond it; delay = frames so seen from the first one to the frame the map emptied it\n\n",
      r.frames, static_cast<unsigned long long>(r.lines), r.min_rays);
  const double bins[] = {0.0, 1.0, 2.0, 3.0, 4.0, 1e9};
  const char* names[] = {"< 1 m", "1-2 m", "2-3 m", "3-4 m", ">= 4 m"};
  experiments::Table t({"ghost cells (first seen at)", "tracked", "seen", "emptied <= 3 seen", "<= 5", "later",
                        "kept", "sunk", "emptied unseen", "unseen, kept", "unseen, sunk", "left window"});
  for (int b = -1; b < 5; ++b) {
    int tracked = 0, seen = 0, in3 = 0, in5 = 0, later = 0, never = 0, sunk = 0, unseen_emptied = 0, unseen_kept = 0,
        unseen_sunk = 0, left = 0;
    for (const TruthTrack& k : r.tracks) {
      if (!k.ghost) continue;
      if (b >= 0 && (k.first_seen < 0 || k.seen_range_m < bins[b] || k.seen_range_m >= bins[b + 1])) continue;
      ++tracked;
      if (k.first_seen < 0) {
        if (k.emptied >= 0) ++unseen_emptied;
        else if (k.ended >= 0) ++left;
        else if (k.sunk >= 0) ++unseen_sunk;
        else ++unseen_kept;
        continue;
      }
      ++seen;
      if (k.emptied < 0) {
        if (k.ended >= 0) ++left;
        else if (k.sunk >= 0) ++sunk;
        else ++never;
      } else if (k.seen_until_emptied <= 3) {
        ++in3;
      } else if (k.seen_until_emptied <= 5) {
        ++in5;
      } else {
        ++later;
      }
    }
    t.add_row({b < 0 ? "all" : names[b], format("%d", tracked), format("%d", seen), format("%d", in3), format("%d", in5),
               format("%d", later), format("%d", never), format("%d", sunk), format("%d", unseen_emptied),
               format("%d", unseen_kept), format("%d", unseen_sunk), format("%d", left)});
  }
  s += t.str();
  s += "\nper ghost cell (layer, centre, first candidate / first seen frame, range, seen frames, emptied, delay):\n";
  for (const TruthTrack& k : r.tracks) {
    if (!k.ghost) continue;
    s += format("  L%d (%.2f, %.2f) w %.2f: from %d, seen %s", k.layer, k.cx, k.cy, k.w, k.first_frame,
                k.first_seen < 0 ? "never" : format("%d at %.2f m", k.first_seen, k.seen_range_m).c_str());
    s += format(", %d seen frames (max %d lines), emptied %s", k.seen_frames, k.max_rays,
                k.emptied < 0 ? (k.ended >= 0  ? format("no (left at %d)", k.ended).c_str()
                                 : k.sunk >= 0 ? format("no (sunk at %d)", k.sunk).c_str()
                                               : "never")
                              : format("%d, delay %d", k.emptied, k.seen_until_emptied).c_str());
    s += "\n";
  }
  s += format("\nGhost cells whose top stands >= %.2f m above the true ground in them but within the clear margin of its\n"
              "lowest point (no line of sight can pass clearly below them), by layer: cells, camera range when first noted\n",
              kRaisedM);
  for (int layer = 0; layer < 8; ++layer) {
    int n = 0;
    double lo = 1e9, hi = 0.0;
    for (const TruthTrack& k : r.within_margin) {
      if (k.layer != layer) continue;
      ++n;
      lo = std::min(lo, k.seen_range_m);
      hi = std::max(hi, k.seen_range_m);
    }
    if (n > 0) s += format("  layer %d: %d cells, %.2f-%.2f m\n", layer, n, lo, hi);
  }
  int real = 0, real_rock = 0, seen_free = 0, seen_rock = 0, lost_free = 0, lost_rock = 0;
  for (const TruthTrack& k : r.tracks) {
    if (k.ghost) continue;
    ++real;
    real_rock += k.rock ? 1 : 0;
    if (k.first_seen >= 0) ++(k.rock ? seen_rock : seen_free);
    if (k.emptied >= 0) ++(k.rock ? lost_rock : lost_free);
  }
  s += format("\nReal side (cells where no rover ever was whose top less the margin stands above the true terrain's\n"
              "lowest point in them): %d cells (%d with a rock); seen clearly below: %d on free ground, %d with a rock;\n"
              "emptied by the map: %d on free ground, %d with a rock\n",
              real, real_rock, seen_free, seen_rock, lost_free, lost_rock);
  for (const TruthTrack& k : r.tracks) {
    if (k.ghost || k.first_seen < 0) continue;
    s += format("  real L%d (%.2f, %.2f)%s: seen from %d at %.2f m, %d frames (max %d lines), emptied %s\n", k.layer,
                k.cx, k.cy, k.rock ? " rock" : "", k.first_seen, k.seen_range_m, k.seen_frames, k.max_rays,
                k.emptied < 0 ? "never" : format("%d", k.emptied).c_str());
  }
  return s;
}

}  // namespace ccmap::traverse
