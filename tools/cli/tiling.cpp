#include "tiling.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <tuple>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/grid/ring_index.hpp"

namespace ccmap::tools {
namespace {

/// floor(a / b) for b > 0.
std::int64_t floor_div(std::int64_t a, std::int64_t b) {
  const std::int64_t q = a / b;
  return (a % b != 0 && a < 0) ? q - 1 : q;
}

/// True if the layer's window holds its cells [lo, hi) on both axes (indices in that layer's cells).
bool window_holds(const MapRunner& runner, int layer, std::int64_t lo, std::int64_t hi) {
  std::int32_t wx = 0, wy = 0;
  runner.layer_window_min(layer, &wx, &wy);
  const std::int64_t side = runner.layer_side(layer);
  return wx <= lo && wy <= lo && hi <= std::int64_t{wx} + side && hi <= std::int64_t{wy} + side;
}

/// A mapped point: its finest cell on the map-frame grid (relative to the origin) and where it
/// comes from.
struct GridPoint {
  std::int64_t gx, gy;  ///< finest cell
  std::int64_t tx, ty;  ///< its tile
  std::uint32_t cloud;
  std::size_t index;
};

struct TileRun {
  std::int64_t tx, ty;
  std::size_t begin, end;  ///< range in the sorted point list
};

bool tile_less(std::int64_t tx_a, std::int64_t ty_a, std::int64_t tx_b, std::int64_t ty_b) {
  return std::tie(ty_a, tx_a) < std::tie(ty_b, tx_b);
}

}  // namespace

bool plan_tiles(MapRunner& runner, const std::vector<double>& widths, std::int32_t max_tile_cells, TilePlan* plan,
                std::string* error) {
  const int layers = runner.layer_count();
  if (static_cast<int>(widths.size()) != layers || layers < 1 || layers > 30) {
    *error = "internal: one cell width per layer expected";
    return false;
  }
  const std::int32_t coarse = std::int32_t{1} << (layers - 1);  // coarsest cell in finest cells
  const std::int32_t margin = runner.layer_is_ccm(0) ? 0 : 1;
  std::int32_t limit = runner.layer_side(0) - 2 * margin;
  if (max_tile_cells > 0) limit = std::min(limit, max_tile_cells);
  const float w0 = runner.layer_cell_width(0);
  for (std::int32_t t = limit / coarse * coarse; t >= coarse; t -= coarse) {
    // Centre of the finest cells [-margin, t + margin) in the tile frame.
    const float centre = static_cast<float>(t) * 0.5F * w0;
    if (!runner.reset(error) || !runner.move_to(centre, centre, error)) return false;
    bool fits = window_holds(runner, 0, -margin, t + margin);
    for (int k = 1; k < layers && fits; ++k) fits = window_holds(runner, k, 0, t >> k);
    if (fits) {
      plan->tile_cells = t;
      plan->margin_cells = margin;
      plan->centre_m = centre;
      plan->widths = widths;
      return runner.reset(error);
    }
  }
  *error = "no tile fits the map's windows (a window narrower than the coarsest cell)";
  return false;
}

bool float_in_cell(double local_m, std::int64_t cell, float inv_width, float* out) {
  // The library's own index of a tile-frame position (it quantises positions before flooring).
  auto index_of = [inv_width](double v, std::int64_t* index) {
    CellIndex c{0, 0};
    if (!grid::index_of_position(static_cast<float>(v), 0.0F, inv_width, &c)) return false;
    *index = c.x;
    return true;
  };
  std::int64_t index = 0;
  if (!index_of(local_m, &index) || index < cell - 1 || index > cell + 1) return false;
  if (index == cell) {
    *out = static_cast<float>(local_m);
    return true;
  }
  // Rounding put it in a neighbour: bisect towards the cell's centre, half a cell inside it,
  // keeping the position nearest to local_m that the library puts in the cell.
  double outside = local_m;
  double inside = (static_cast<double>(cell) + 0.5) / static_cast<double>(inv_width);
  if (!index_of(inside, &index) || index != cell) return false;
  for (int step = 0; step < 64; ++step) {
    const double mid = 0.5 * (outside + inside);
    if (index_of(mid, &index) && index == cell) {
      inside = mid;
    } else {
      outside = mid;
    }
  }
  *out = static_cast<float>(inside);
  return true;
}

LayerCellRow make_row(int layer, std::int64_t ix, std::int64_t iy, double width, double z_origin,
                      const LocalCell& c) {
  LayerCellRow r;
  r.layer = layer;
  r.ix = ix;
  r.iy = iy;
  r.cx = (static_cast<double>(ix) + 0.5) * width;
  r.cy = (static_cast<double>(iy) + 0.5) * width;
  r.res = width;
  r.weight = c.weight;
  r.height = static_cast<double>(c.height) + z_origin;
  r.slope_x = c.slope_x;
  r.slope_y = c.slope_y;
  r.normal_var = c.normal_variance;
  r.elev_var = c.elevation_variance;
  r.cell_class = c.cell_class;
  return r;
}

bool map_tiled(MapRunner& runner, const TilePlan& plan, const std::vector<Cloud>& clouds, const LocalOrigin& origin,
               const AreaBounds& bounds, std::ostream* progress, TileQuery* query, TiledMap* result,
               std::string* error) {
  const int layers = runner.layer_count();
  const std::int64_t t_cells = plan.tile_cells;
  const std::int64_t margin = plan.margin_cells;
  const double w0 = plan.widths.at(0);
  const float inv_w0 = 1.0F / runner.layer_cell_width(0);  // the value the library's index uses
  const std::int64_t coarse = std::int64_t{1} << (layers - 1);
  result->layers.assign(static_cast<std::size_t>(layers), {});
  result->frames.assign(clouds.size(), FrameStats{});
  result->frame_ms.assign(clouds.size(), 0.0);
  result->tiles = 0;

  // 1. Classify every point and give the mapped ones their finest cell (double, map grid).
  std::vector<GridPoint> points;
  for (std::size_t f = 0; f < clouds.size(); ++f) {
    const Cloud& c = clouds[f];
    FrameStats& s = result->frames[f];
    s.received = c.size() + c.skipped_non_finite;
    s.rejected_non_finite = c.skipped_non_finite;
    for (std::size_t i = 0; i < c.size(); ++i) {
      const PointFate fate = classify_point(c.x[i], c.y[i], c.z[i], origin, bounds);
      if (fate == PointFate::kOutOfRange) {
        ++s.rejected_out_of_range;
      } else if (fate == PointFate::kOutsideBounds) {
        ++s.outside_map;
      } else {
        // |x - origin| <= 1e5 m and w0 >= 0.19 mm: |index| < 2^30, exact in double and int64.
        GridPoint p{static_cast<std::int64_t>(std::floor((c.x[i] - origin.xyz[0]) / w0)),
                    static_cast<std::int64_t>(std::floor((c.y[i] - origin.xyz[1]) / w0)), 0, 0,
                    static_cast<std::uint32_t>(f), i};
        p.tx = floor_div(p.gx, t_cells);
        p.ty = floor_div(p.gy, t_cells);
        points.push_back(p);
      }
    }
  }
  // 2. Group by tile (rows of tiles, increasing y then x), file order inside a tile.
  std::sort(points.begin(), points.end(), [](const GridPoint& a, const GridPoint& b) {
    return std::tie(a.ty, a.tx, a.cloud, a.index) < std::tie(b.ty, b.tx, b.cloud, b.index);
  });
  std::vector<TileRun> runs;
  for (std::size_t i = 0; i < points.size();) {
    const std::int64_t tx = points[i].tx, ty = points[i].ty;
    std::size_t j = i;
    while (j < points.size() && points[j].tx == tx && points[j].ty == ty) ++j;
    runs.push_back(TileRun{tx, ty, i, j});
    i = j;
  }
  auto find_run = [&](std::int64_t tx, std::int64_t ty) -> const TileRun* {
    const auto it = std::lower_bound(runs.begin(), runs.end(), std::make_pair(tx, ty),
                                     [](const TileRun& r, const std::pair<std::int64_t, std::int64_t>& k) {
                                       return tile_less(r.tx, r.ty, k.first, k.second);
                                     });
    return (it != runs.end() && it->tx == tx && it->ty == ty) ? &*it : nullptr;
  };

  std::vector<const TileRun*> selected;
  const double range = static_cast<double>(kMaxAbsCoordinateM);
  if (query != nullptr && query->wanted &&
      !(std::fabs(query->x - origin.xyz[0]) <= range && std::fabs(query->y - origin.xyz[1]) <= range)) {
    query->mapped = false;  // beyond the library's range from the origin: no tile there
  } else if (query != nullptr && query->wanted) {
    const std::int64_t qx = static_cast<std::int64_t>(std::floor((query->x - origin.xyz[0]) / w0));
    const std::int64_t qy = static_cast<std::int64_t>(std::floor((query->y - origin.xyz[1]) / w0));
    const std::int64_t tx = floor_div(qx, t_cells), ty = floor_div(qy, t_cells);
    query->mapped = false;
    if (const TileRun* run = find_run(tx, ty)) {
      selected.push_back(run);
      const double lx = (query->x - origin.xyz[0]) - static_cast<double>(tx * t_cells) * w0;
      const double ly = (query->y - origin.xyz[1]) - static_cast<double>(ty * t_cells) * w0;
      if (!float_in_cell(lx, qx - tx * t_cells, inv_w0, &query->local_x) ||
          !float_in_cell(ly, qy - ty * t_cells, inv_w0, &query->local_y)) {
        *error = "internal: the query point has no float position in its cell";
        return false;
      }
      query->mapped = true;
    }
  } else {
    for (const TileRun& r : runs) selected.push_back(&r);
  }

  // 3. Map tile by tile.
  const auto start = std::chrono::steady_clock::now();
  std::vector<float> xyz, weights;
  std::vector<LocalCell> cells;
  std::vector<const GridPoint*> core, ring;
  std::size_t next_report = 1, points_done = 0;
  for (std::size_t n = 0; n < selected.size(); ++n) {
    const TileRun& run = *selected[n];
    const std::int64_t x0 = run.tx * t_cells, y0 = run.ty * t_cells;  // first finest cell of the tile
    if (!runner.reset(error) || !runner.move_to(plan.centre_m, plan.centre_m, error)) return false;
    // The margin: points of the 8 neighbouring tiles in the ring of finest cells around this one.
    ring.clear();
    for (std::int64_t dy = -1; dy <= 1 && margin > 0; ++dy) {
      for (std::int64_t dx = -1; dx <= 1; ++dx) {
        const TileRun* nb = (dx == 0 && dy == 0) ? nullptr : find_run(run.tx + dx, run.ty + dy);
        if (nb == nullptr) continue;
        for (std::size_t i = nb->begin; i < nb->end; ++i) {
          const GridPoint& p = points[i];
          if (p.gx >= x0 - margin && p.gx < x0 + t_cells + margin && p.gy >= y0 - margin &&
              p.gy < y0 + t_cells + margin) {
            ring.push_back(&p);
          }
        }
      }
    }
    std::sort(ring.begin(), ring.end(), [](const GridPoint* a, const GridPoint* b) {
      return std::tie(a->cloud, a->index) < std::tie(b->cloud, b->index);
    });
    // Sensor at the local origin, in this tile's frame (only the stereo model's noise uses it).
    const float sensor[3] = {
        static_cast<float>(std::clamp(-static_cast<double>(x0) * w0, -1e5, 1e5)),
        static_cast<float>(std::clamp(-static_cast<double>(y0) * w0, -1e5, 1e5)), 0.0F};
    // One frame per cloud: its core points, then (counters discarded) its margin points.
    std::size_t ring_at = 0;
    std::size_t core_at = run.begin;
    for (std::uint32_t f = 0; f < clouds.size(); ++f) {
      core.clear();
      while (core_at < run.end && points[core_at].cloud == f) core.push_back(&points[core_at++]);
      const std::size_t ring_begin = ring_at;
      while (ring_at < ring.size() && ring[ring_at]->cloud == f) ++ring_at;
      for (int part = 0; part < 2; ++part) {
        const std::size_t count = part == 0 ? core.size() : ring_at - ring_begin;
        if (count == 0) continue;
        const Cloud& c = clouds[f];
        xyz.resize(3 * count);
        weights.clear();
        for (std::size_t i = 0; i < count; ++i) {
          const GridPoint& p = part == 0 ? *core[i] : *ring[ring_begin + i];
          const double lx = (c.x[p.index] - origin.xyz[0]) - static_cast<double>(x0) * w0;
          const double ly = (c.y[p.index] - origin.xyz[1]) - static_cast<double>(y0) * w0;
          if (!float_in_cell(lx, p.gx - x0, inv_w0, &xyz[3 * i]) ||
              !float_in_cell(ly, p.gy - y0, inv_w0, &xyz[3 * i + 1])) {
            *error = "internal: a point has no float position in its cell";
            return false;
          }
          xyz[3 * i + 2] = static_cast<float>(c.z[p.index] - origin.xyz[2]);
          if (c.has_weight) weights.push_back(weight_to_float(c.w[p.index]));
        }
        FrameStats stats;
        const auto t0 = std::chrono::steady_clock::now();
        if (!runner.update_frame(xyz, weights, sensor, &stats, error)) return false;
        if (part == 0) {
          result->frame_ms[f] += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
          stats.received = 0;  // counted once per point above
          result->frames[f].add(stats);
          points_done += count;
        }
      }
    }
    ++result->tiles;
    if (query == nullptr || !query->wanted) {
      for (int k = 0; k < layers; ++k) {
        if (!runner.export_layer(k, &cells, error)) return false;
        const std::int64_t side = t_cells >> k;  // the tile in layer-k cells
        const std::int64_t scale = coarse >> k;  // coarsest cell in layer-k cells
        for (const LocalCell& c : cells) {
          if (c.ix < 0 || c.iy < 0 || c.ix >= side || c.iy >= side) continue;  // margin or beyond
          const std::int64_t ix = origin.cells[0] * scale + run.tx * side + c.ix;
          const std::int64_t iy = origin.cells[1] * scale + run.ty * side + c.iy;
          result->layers[static_cast<std::size_t>(k)].push_back(
              make_row(k, ix, iy, plan.widths[static_cast<std::size_t>(k)], origin.xyz[2], c));
        }
      }
    }
    if (progress != nullptr && (n + 1) * 10 >= next_report * selected.size()) {
      *progress << "progress: " << (n + 1) << " of " << selected.size() << " tiles ("
                << (n + 1) * 100 / selected.size() << " %), " << points_done << " points, "
                << std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - start)
                       .count()
                << " ms\n";
      while ((n + 1) * 10 >= next_report * selected.size()) ++next_report;
    }
  }
  for (std::vector<LayerCellRow>& rows : result->layers) {
    std::sort(rows.begin(), rows.end(), [](const LayerCellRow& a, const LayerCellRow& b) {
      return std::tie(a.iy, a.ix) < std::tie(b.iy, b.ix);
    });
  }
  return true;
}

}  // namespace ccmap::tools
