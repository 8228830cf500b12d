#include "cli.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <sstream>
#include <string>
#include <system_error>
#include <vector>

#include "ccmap/cell/ccm_cell.hpp"
#include "cloud_reader.hpp"
#include "csv_writer.hpp"
#include "layer_images.hpp"
#include "map_runner.hpp"
#include "origin.hpp"
#include "tiling.hpp"

namespace ccmap::tools {
namespace {

constexpr const char* kMainHelp =
    "usage: ccmap <command> [options]\n"
    "\n"
    "Builds Converging Covariance Maps (CCM) from point clouds.\n"
    "\n"
    "commands:\n"
    "  map     map clouds and write per-layer CSV files and pictures\n"
    "  query   map clouds and print the map's answer at one point\n"
    "\n"
    "Run 'ccmap map --help' or 'ccmap query --help' for the options.\n";

constexpr const char* kMapHelp =
    "usage: ccmap map --preset NAME --cloud FILE [--cloud FILE ...] --out DIR\n"
    "                 [--res METRES] [--wl W_L] [--poses FILE] [--sensor lidar|stereo] [--sigma METRES]\n"
    "                 [--bounds XMIN,YMIN,XMAX,YMAX] [--paper-cell]\n"
    "\n"
    "  --preset NAME   cadre: 4 cm piece-wise constant Kalman layer, then 8/16/32/64 cm CCM layers\n"
    "                  ccm, kf, omg: one 256 x 256 layer of CCM, Kalman or OMG cells\n"
    "  --paper-cell    CCM cells of the paper's 9 floats (slopes per axis, eq. 9; coverage per\n"
    "                  axis, eq. 12) instead of the full cell with the lateral covariance (the\n"
    "                  least-squares plane; coverage by the smaller eigenvalue); cadre and ccm only\n"
    "  --res METRES    finest cell width (default 0.04 for cadre, 0.08 otherwise); the layers of\n"
    "                  cadre keep their 1:2:4:8:16 ratios\n"
    "  --wl W_L        weight limit W_l of CCM and OMG cells (default 1000)\n"
    "  --cloud FILE    one frame, map-frame coordinates: .ply (ascii/binary), .las (1.0-1.4,\n"
    "                  uncompressed) or text 'x y z [w]' per line; repeat for more frames,\n"
    "                  applied in order. A per-point weight (PLY property, 4th text column)\n"
    "                  replaces the sensor model's weight for CCM and OMG cells (Kalman cells\n"
    "                  weigh by range variance); weights <= 0 or non-finite are counted as bad.\n"
    "  --poses FILE    one line 'x y z yaw' per frame: the sensor position in the map frame; the\n"
    "                  map is re-centred on (x, y) before the frame and follows the poses like a\n"
    "                  rover's map: points beyond its windows count as outside map.\n"
    "  --sensor NAME   lidar (default): constant range noise --sigma (default 0.005 m);\n"
    "                  stereo: the CADRE stereo model (noise grows with range^2 from the pose;\n"
    "                  without --poses, from the local origin)\n"
    "  --bounds XMIN,YMIN,XMAX,YMAX\n"
    "                  map only the points inside this map-frame rectangle (absolute coordinates,\n"
    "                  edges included); the others count as outside map\n"
    "  --out DIR       writes DIR/layer_<k>.csv (finest first) and layer_<k>_{height,slope,\n"
    "                  normal_var,class}.png; class colours: unknown grey, traversable green,\n"
    "                  obstacle red, steep orange, unobserved black\n"
    "\n"
    "Without --poses the whole of every cloud is mapped: the tool sweeps the stack over the\n"
    "clouds in tiles (move the stack to a tile, fold the tile's points, export the tile's cells),\n"
    "so every layer covers the clouds' extent and every point's cell appears once in each layer's\n"
    "CSV, with all the points that fall in it. While its tile is mapped a point lies inside every\n"
    "layer's window, so only its range noise routes it: with the lidar model every point goes to\n"
    "the finest layer its noise allows (cadre: the Kalman layer while --sigma <= res / (4 sqrt 3),\n"
    "5.8 mm for 4 cm cells) and the coarser layers answer by pooling their 2 x 2 children (paper\n"
    "Section IV-F), as the cells next to a rover do. A progress line follows every tenth of the\n"
    "tiles.\n"
    "\n"
    "Coordinates may be absolute (e.g. UTM): the tool subtracts a local origin (the per-axis\n"
    "median of the points, rounded to the coarsest cell width; with --poses, of the first cloud)\n"
    "in double precision before the float library sees them, and adds it back to every output\n"
    "coordinate and height. Points beyond +-1e9 m, or farther than 1e5 m (the library's range)\n"
    "from the origin on an axis, are counted as out of range.\n";

constexpr const char* kQueryHelp =
    "usage: ccmap query --preset NAME --cloud FILE [--cloud FILE ...] --at X,Y\n"
    "                   [--res METRES] [--wl W_L] [--poses FILE] [--sensor lidar|stereo] [--sigma METRES]\n"
    "                   [--bounds XMIN,YMIN,XMAX,YMAX] [--paper-cell]\n"
    "\n"
    "Maps the clouds as 'ccmap map' does (same options, see 'ccmap map --help') and prints the\n"
    "map's answer at the map-frame point (X, Y): layer, height, slopes, inclination, normal\n"
    "variance, elevation variance and class, one 'key: value' per line. Without --poses only the\n"
    "tile that holds (X, Y) is mapped (the answer is the whole map's); a point whose tile holds no\n"
    "point of the clouds is outside the map (status: outside_map).\n";

/// Thrown inside this file only, turned into "ccmap: error: ..." by run_cli.
struct CliError {
  std::string message;
  int code;
};
[[noreturn]] void fail(const std::string& message, int code = 1) { throw CliError{message, code}; }

std::string fmt(const char* format, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

double parse_number(const std::string& flag, const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || std::isspace(static_cast<unsigned char>(text[0]))) {
    fail(flag + ": '" + text + "' is not a number", 2);
  }
  return v;
}

double parse_positive(const std::string& flag, const std::string& text, double max, bool allow_inf = false) {
  const double v = parse_number(flag, text);
  if (std::isnan(v) || !(v > 0.0) || (!allow_inf && !std::isfinite(v)) || (std::isfinite(v) && v > max)) {
    fail(flag + ": " + text + " is out of range (expected a number > 0" +
             (std::isfinite(max) ? " and <= " + fmt("%g", max) : std::string()) + ")",
         2);
  }
  return v;
}

/// --bounds XMIN,YMIN,XMAX,YMAX: four finite numbers, minimum below maximum on both axes.
AreaBounds parse_bounds(const std::string& text) {
  double v[4] = {0.0, 0.0, 0.0, 0.0};
  std::size_t at = 0;
  for (int i = 0; i < 4; ++i) {
    const std::size_t comma = i < 3 ? text.find(',', at) : text.size();
    if (comma == std::string::npos || (i == 3 && text.find(',', at) != std::string::npos)) {
      fail("--bounds: expected XMIN,YMIN,XMAX,YMAX, got '" + text + "'", 2);
    }
    v[i] = parse_number("--bounds", text.substr(at, comma - at));
    if (!std::isfinite(v[i])) fail("--bounds: coordinates must be finite", 2);
    at = comma + 1;
  }
  if (!(v[0] < v[2]) || !(v[1] < v[3])) fail("--bounds: XMIN < XMAX and YMIN < YMAX expected, got '" + text + "'", 2);
  AreaBounds b;
  b.set = true;
  b.x_min = v[0];
  b.y_min = v[1];
  b.x_max = v[2];
  b.y_max = v[3];
  return b;
}

struct Options {
  std::string command;
  std::string preset;
  double res = 0.0;
  double wl = 0.0;
  std::vector<std::string> clouds;
  std::string poses;
  std::string out_dir;
  bool have_at = false;
  double at_x = 0.0, at_y = 0.0;
  SensorChoice sensor = SensorChoice::kLidar;
  double sigma = 0.005;
  AreaBounds bounds;
  bool paper_cell = false;
  bool help = false;
};

Options parse_options(int argc, char** argv) {
  Options o;
  o.command = argv[1];
  for (int i = 2; i < argc; ++i) {
    std::string arg = argv[i];
    std::string value;
    bool have_value = false;
    if (arg == "--help" || arg == "-h") {
      o.help = true;
      continue;
    }
    if (arg == "--paper-cell") {
      o.paper_cell = true;
      continue;
    }
    if (arg.rfind("--", 0) != 0) fail("unexpected argument '" + arg + "' (options start with --)", 2);
    const std::size_t eq = arg.find('=');
    if (eq != std::string::npos) {
      value = arg.substr(eq + 1);
      arg = arg.substr(0, eq);
      have_value = true;
    }
    static const char* kKnown[] = {"--preset", "--res", "--wl", "--cloud", "--poses", "--out", "--at", "--sensor", "--sigma", "--bounds"};
    if (std::find_if(std::begin(kKnown), std::end(kKnown), [&](const char* k) { return arg == k; }) == std::end(kKnown)) {
      fail("unknown option '" + arg + "' (see 'ccmap " + o.command + " --help')", 2);
    }
    if (!have_value) {
      if (i + 1 >= argc) fail(arg + " needs a value", 2);
      value = argv[++i];
    }
    if (arg == "--preset") {
      o.preset = value;
    } else if (arg == "--res") {
      o.res = parse_positive(arg, value, 100.0);
    } else if (arg == "--wl") {
      o.wl = parse_positive(arg, value, 1e30, /*allow_inf=*/true);
    } else if (arg == "--cloud") {
      if (value.empty()) fail("--cloud needs a file name", 2);
      o.clouds.push_back(value);
    } else if (arg == "--poses") {
      o.poses = value;
    } else if (arg == "--out") {
      if (value.empty()) fail("--out needs a directory", 2);
      o.out_dir = value;
    } else if (arg == "--at") {
      const std::size_t comma = value.find(',');
      if (comma == std::string::npos) fail("--at: expected X,Y, got '" + value + "'", 2);
      o.at_x = parse_number("--at", value.substr(0, comma));
      o.at_y = parse_number("--at", value.substr(comma + 1));
      if (!std::isfinite(o.at_x) || !std::isfinite(o.at_y)) fail("--at: coordinates must be finite", 2);
      o.have_at = true;
    } else if (arg == "--sensor") {
      if (value == "lidar") o.sensor = SensorChoice::kLidar;
      else if (value == "stereo") o.sensor = SensorChoice::kCadreStereo;
      else fail("--sensor: unknown sensor '" + value + "' (expected lidar or stereo)", 2);
    } else if (arg == "--sigma") {
      o.sigma = parse_positive(arg, value, 10.0);
    } else if (arg == "--bounds") {
      o.bounds = parse_bounds(value);
    }
  }
  return o;
}

std::string base_name(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

/// A mapped sequence: the runner, the local origin, the per-frame accounting and, for a tiled
/// map, the exported rows.
struct MappedClouds {
  std::unique_ptr<MapRunner> runner;
  LocalOrigin origin;
  std::vector<double> widths;          ///< requested cell width per layer (m), finest first
  FrameStats totals;
  std::uint64_t read = 0;
  bool tiled = false;                  ///< no --poses: the stack was swept over the clouds
  std::vector<std::vector<LayerCellRow>> rows;  ///< tiled: the rows of every layer
  TileQuery query;                     ///< tiled query: where the answer is
};

const char* sensor_name(const Options& o) {
  return o.sensor == SensorChoice::kLidar ? "lidar" : "stereo (CADRE model)";
}

Cloud read_nonempty_cloud(const std::string& path) {
  Cloud cloud = read_cloud(path);
  if (!cloud.ok()) fail(cloud.error);
  if (cloud.size() == 0) {
    fail(path + ": empty cloud (" + std::to_string(cloud.declared) + " points, " +
         std::to_string(cloud.skipped_non_finite) + " of them non-finite)");
  }
  return cloud;
}

void print_header(const Options& o, const MappedClouds& m, std::ostream& out) {
  out << "ccmap " << o.command << ": preset " << o.preset << ", " << m.widths.size() << " layer(s), cell widths";
  for (double w : m.widths) out << ' ' << fmt("%g", w);
  out << " m, W_l " << fmt("%g", m.runner->weight_limit()) << ", min weight " << fmt("%g", m.runner->min_weight())
      << ", sensor " << sensor_name(o);
  if (o.sensor == SensorChoice::kLidar) out << " (sigma " << fmt("%g", o.sigma) << " m)";
  if (preset_has_ccm(o.preset)) out << ", CCM cell " << (o.paper_cell ? "paper (9 floats)" : "full (10 floats)");
  out << "\n";
  out << "origin (map frame): " << fmt("%.3f", m.origin.xyz[0]) << ' ' << fmt("%.3f", m.origin.xyz[1]) << ' '
      << fmt("%.3f", m.origin.xyz[2]) << "  (per-axis median of the " << (o.poses.empty() ? "" : "first cloud's ")
      << "points in range, rounded to " << fmt("%g", m.origin.coarsest_width) << " m)\n";
  if (o.bounds.set) {
    out << "bounds: x " << fmt("%.3f", o.bounds.x_min) << " .. " << fmt("%.3f", o.bounds.x_max) << ", y "
        << fmt("%.3f", o.bounds.y_min) << " .. " << fmt("%.3f", o.bounds.y_max)
        << " (points outside are counted as outside map)\n";
  }
}

std::string counts_text(const FrameStats& s) {
  return "used " + std::to_string(s.used) + ", rejected: non-finite " + std::to_string(s.rejected_non_finite) +
         ", out of range " + std::to_string(s.rejected_out_of_range) + ", bad weight " +
         std::to_string(s.rejected_weight) + ", outside map " + std::to_string(s.outside_map) + ", too noisy " +
         std::to_string(s.too_noisy);
}

void print_frame(const std::string& path, const Cloud& cloud, std::size_t f, const FrameStats& stats, double ms,
                 std::ostream& out) {
  out << "frame " << (f + 1) << ": " << base_name(path) << " [" << cloud.format << "]: " << cloud.declared
      << " points, " << counts_text(stats) << "; " << fmt("%.1f", ms) << " ms\n";
  if (cloud.has_weight) {
    out << "note: " << base_name(path) << ": per-point weights from the file replace the sensor model's\n";
  }
}

/// With --poses: the stack follows the poses, one frame per cloud, read and mapped one at a time.
void map_along_poses(const Options& o, MappedClouds& m, std::ostream& out, bool verbose) {
  std::string error;
  std::vector<Pose> poses;
  if (!read_poses(o.poses, &poses, &error)) fail(error);
  if (poses.size() != o.clouds.size()) {
    fail(o.poses + ": " + std::to_string(poses.size()) + " poses for " + std::to_string(o.clouds.size()) +
         " clouds (one line per --cloud expected)");
  }
  std::vector<float> xyz, weights;
  for (std::size_t f = 0; f < o.clouds.size(); ++f) {
    const Cloud cloud = read_nonempty_cloud(o.clouds[f]);
    m.read += cloud.declared;
    if (f == 0) {
      if (!robust_origin({&cloud}, o.bounds, m.widths.back(), &m.origin, &error)) fail(o.clouds[f] + ": " + error);
      if (verbose) print_header(o, m, out);
    }
    // Pose: re-centre, and the sensor origin for the noise model (local frame).
    const Pose& p = poses[f];
    const double pose_local[3] = {p.x - m.origin.xyz[0], p.y - m.origin.xyz[1], p.z - m.origin.xyz[2]};
    for (double v : pose_local) {
      if (!(std::fabs(v) <= static_cast<double>(kMaxAbsCoordinateM))) {
        fail(o.poses + ": pose " + std::to_string(f + 1) + " lies beyond +-1e5 m of the origin; is it in the clouds' frame?");
      }
    }
    const float sensor[3] = {static_cast<float>(pose_local[0]), static_cast<float>(pose_local[1]),
                             static_cast<float>(pose_local[2])};
    if (!m.runner->move_to(sensor[0], sensor[1], &error)) {
      fail(o.poses + ": pose " + std::to_string(f + 1) + ": " + error + "; is it in the clouds' frame?");
    }
    FrameStats stats;
    stats.received = cloud.size() + cloud.skipped_non_finite;
    stats.rejected_non_finite = cloud.skipped_non_finite;
    xyz.clear();
    weights.clear();
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      const PointFate fate = classify_point(cloud.x[i], cloud.y[i], cloud.z[i], m.origin, o.bounds);
      if (fate == PointFate::kOutOfRange) {
        ++stats.rejected_out_of_range;
        continue;
      }
      if (fate == PointFate::kOutsideBounds) {
        ++stats.outside_map;
        continue;
      }
      // Subtract the origin in double, then round to float (|difference| <= 1e5 m).
      xyz.push_back(static_cast<float>(cloud.x[i] - m.origin.xyz[0]));
      xyz.push_back(static_cast<float>(cloud.y[i] - m.origin.xyz[1]));
      xyz.push_back(static_cast<float>(cloud.z[i] - m.origin.xyz[2]));
      if (cloud.has_weight) weights.push_back(weight_to_float(cloud.w[i]));
    }
    FrameStats lib;
    const auto t0 = std::chrono::steady_clock::now();
    if (!m.runner->update_frame(xyz, weights, sensor, &lib, &error)) fail(o.clouds[f] + ": " + error);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    lib.received = 0;  // counted above, with the points the tool kept back
    stats.add(lib);
    m.totals.add(stats);
    if (verbose) print_frame(o.clouds[f], cloud, f, stats, ms, out);
  }
}

/// Without --poses: the stack is swept over all clouds in tiles (tiling.hpp), so every layer
/// covers their whole extent. For a query only the query point's tile is mapped.
void map_in_tiles(const Options& o, MappedClouds& m, std::ostream& out, bool verbose) {
  std::string error;
  std::vector<Cloud> clouds;
  std::vector<const Cloud*> all;
  clouds.reserve(o.clouds.size());
  for (const std::string& path : o.clouds) {
    clouds.push_back(read_nonempty_cloud(path));
    m.read += clouds.back().declared;
  }
  for (const Cloud& c : clouds) all.push_back(&c);
  if (!robust_origin(all, o.bounds, m.widths.back(), &m.origin, &error)) fail(error);
  if (verbose) print_header(o, m, out);
  TilePlan plan;
  if (!plan_tiles(*m.runner, m.widths, 0, &plan, &error)) fail(error);
  m.query.wanted = o.have_at;
  m.query.x = o.at_x;
  m.query.y = o.at_y;
  if (verbose && !o.have_at) {
    out << "tiles: " << plan.tile_cells << " x " << plan.tile_cells << " cells of " << fmt("%g", m.widths[0])
        << " m (" << fmt("%g", plan.tile_cells * m.widths[0]) << " m), each mapped alone"
        << (plan.margin_cells > 0 ? " with its 1-cell ring of neighbours" : "") << "; every layer covers the clouds\n";
  }
  TiledMap map;
  if (!map_tiled(*m.runner, plan, clouds, m.origin, o.bounds, verbose ? &out : nullptr, &m.query, &map, &error)) {
    fail(error);
  }
  m.tiled = true;
  m.rows = std::move(map.layers);
  for (std::size_t f = 0; f < clouds.size(); ++f) {
    m.totals.add(map.frames[f]);
    if (verbose) print_frame(o.clouds[f], clouds[f], f, map.frames[f], map.frame_ms[f], out);
  }
  if (verbose && !o.have_at) out << "tiles mapped: " << map.tiles << "\n";
}

MappedClouds build_map(const Options& o, std::ostream& out, bool verbose) {
  if (o.preset.empty()) fail("--preset is required (cadre, ccm, kf or omg)", 2);
  std::string error;
  MappedClouds m;
  m.runner = make_map_runner(o.preset, o.paper_cell, &error);
  if (!m.runner) fail(error, 2);
  if (o.clouds.empty()) fail("at least one --cloud FILE is required", 2);

  const int layers = preset_layer_count(o.preset);
  const double finest = o.res > 0.0 ? o.res : preset_default_cell_width(o.preset);
  for (int k = 0; k < layers; ++k) m.widths.push_back(finest * std::ldexp(1.0, k));

  RunnerOptions ro;
  ro.preset = o.preset;
  ro.finest_cell_width_m = finest;
  ro.weight_limit = o.wl;
  ro.sensor = o.sensor;
  ro.lidar_sigma_m = o.sigma;
  if (!m.runner->init(ro, &error)) fail(error);

  if (o.poses.empty()) {
    map_in_tiles(o, m, out, verbose);
  } else {
    map_along_poses(o, m, out, verbose);
  }
  if (verbose) out << "points: read " << m.read << ", " << counts_text(m.totals) << "\n";
  return m;
}

/// Layer rows of the runner's current state in the map frame (origin added back in double).
std::vector<LayerCellRow> layer_rows(const MappedClouds& m, int layer, const std::vector<LocalCell>& cells) {
  const double res = m.widths[static_cast<std::size_t>(layer)];
  const std::int64_t scale = std::int64_t{1} << (static_cast<int>(m.widths.size()) - 1 - layer);
  std::vector<LayerCellRow> rows;
  rows.reserve(cells.size());
  for (const LocalCell& c : cells) {
    rows.push_back(make_row(layer, static_cast<std::int64_t>(c.ix) + m.origin.cells[0] * scale,
                            static_cast<std::int64_t>(c.iy) + m.origin.cells[1] * scale, res, m.origin.xyz[2], c));
  }
  return rows;
}

int run_map(const Options& o, std::ostream& out) {
  if (o.out_dir.empty()) fail("--out DIR is required", 2);
  if (o.have_at) fail("--at belongs to 'ccmap query'", 2);
  MappedClouds m = build_map(o, out, true);
  std::error_code ec;
  std::filesystem::create_directories(o.out_dir, ec);
  if (ec || !std::filesystem::is_directory(o.out_dir)) {
    fail("cannot create output directory '" + o.out_dir + "'" + (ec ? ": " + ec.message() : std::string()));
  }
  std::string error;
  for (int k = 0; k < m.runner->layer_count(); ++k) {
    std::vector<LayerCellRow> rows;
    if (m.tiled) {
      rows = std::move(m.rows[static_cast<std::size_t>(k)]);
    } else {
      std::vector<LocalCell> cells;
      if (!m.runner->export_layer(k, &cells, &error)) fail(error);
      rows = layer_rows(m, k, cells);
    }
    const std::string prefix = o.out_dir + "/layer_" + std::to_string(k);
    if (!write_layer_csv(prefix + ".csv", rows, &error)) fail(error);
    // Pictures show the bounding box of the observed cells (a small scan in a large layer
    // would otherwise be a speck); a layer with no observed cell is drawn as its window around
    // the origin, black.
    const std::int64_t scale = std::int64_t{1} << (static_cast<int>(m.widths.size()) - 1 - k);
    const int side = m.runner->layer_side(k);
    LayerWindow window{};
    if (rows.empty()) {
      window = LayerWindow{m.origin.cells[0] * scale - side / 2, m.origin.cells[1] * scale - side / 2, side, side};
    }
    const LayerWindow extent = layer_extent(rows, window);
    if (extent.nx > kMaxImageCells || extent.ny > kMaxImageCells) {
      out << "note: layer " << k << " spans " << extent.nx << " x " << extent.ny << " cells, more than the "
          << kMaxImageCells << " a picture may have: no pictures for it (the CSV holds every cell)\n";
    } else if (!write_layer_images(prefix, rows, window, &error)) {
      fail(error);
    }
    std::size_t counts[4] = {0, 0, 0, 0};
    for (const LayerCellRow& r : rows) {
      if (r.cell_class == "traversable") ++counts[1];
      else if (r.cell_class == "obstacle") ++counts[2];
      else if (r.cell_class == "steep") ++counts[3];
      else ++counts[0];
    }
    out << "layer " << k << " (" << fmt("%g", m.widths[static_cast<std::size_t>(k)]) << " m, "
        << (m.tiled ? "tiled" : std::to_string(side) + " x " + std::to_string(side)) << ", "
        << (m.runner->layer_is_ccm(k) ? "CCM" : (o.preset == "omg" ? "OMG" : "Kalman"))
        << "): " << (rows.size() - counts[0]) << " cells known of " << rows.size() << " observed (traversable "
        << counts[1] << ", obstacle " << counts[2] << ", steep " << counts[3] << ", unknown " << counts[0]
        << ") -> " << prefix << ".csv\n";
  }
  out << "pictures: " << o.out_dir << "/layer_<k>_{height,slope,normal_var,class}.png, north up, observed area"
      << " (class: unknown grey, traversable green, obstacle red, steep orange; unobserved black)\n";
  return 0;
}

int run_query(const Options& o, std::ostream& out) {
  if (!o.have_at) fail("--at X,Y is required", 2);
  if (!o.out_dir.empty()) fail("--out belongs to 'ccmap map'", 2);
  std::ostringstream log;
  MappedClouds m = build_map(o, log, true);
  LocalQuery q;
  q.status = "outside_map";  // a tiled map holds only the tiles that hold points
  if (!m.tiled) {
    const double lx = o.at_x - m.origin.xyz[0], ly = o.at_y - m.origin.xyz[1];
    if (std::fabs(lx) <= static_cast<double>(kMaxAbsCoordinateM) && std::fabs(ly) <= static_cast<double>(kMaxAbsCoordinateM)) {
      q = m.runner->query(static_cast<float>(lx), static_cast<float>(ly));
    }
  } else if (m.query.mapped) {
    q = m.runner->query(m.query.local_x, m.query.local_y);
  }
  const double kPi = 3.14159265358979323846;
  out << "x: " << fmt("%.6f", o.at_x) << "\n";
  out << "y: " << fmt("%.6f", o.at_y) << "\n";
  out << "status: " << q.status << "\n";
  out << "layer: " << q.layer << "\n";
  const bool layer_ok = q.layer >= 0 && q.layer < static_cast<int>(m.widths.size());
  out << "cell_width_m: " << fmt("%g", layer_ok ? m.widths[static_cast<std::size_t>(q.layer)] : 0.0)
      << "\n";
  const bool ok = q.status == "ok";
  out << "height_m: " << (ok ? fmt("%.6f", static_cast<double>(q.height) + m.origin.xyz[2]) : std::string("nan")) << "\n";
  out << "slope_x: " << fmt("%.6g", q.slope_x) << "\n";
  out << "slope_y: " << fmt("%.6g", q.slope_y) << "\n";
  out << "inclination: " << fmt("%.6g", q.inclination) << "\n";
  out << "inclination_deg: " << fmt("%.3f", std::atan(static_cast<double>(q.inclination)) * 180.0 / kPi) << "\n";
  out << "normal_variance_m2: " << fmt("%.6g", q.normal_variance) << "\n";
  out << "elevation_variance_m2: " << fmt("%.6g", q.elevation_variance) << "\n";
  out << "weight: " << fmt("%.6g", q.weight) << "\n";
  out << "class: " << q.cell_class << "\n";
  return 0;
}

}  // namespace

int run_cli(int argc, char** argv, std::ostream& out, std::ostream& err) {
  try {
    if (argc < 2 || argv == nullptr) {
      err << kMainHelp;
      return 2;
    }
    const std::string command = argv[1];
    if (command == "--help" || command == "-h" || command == "help") {
      out << kMainHelp;
      return 0;
    }
    if (command != "map" && command != "query") fail("unknown command '" + command + "' (expected map or query)", 2);
    const Options o = parse_options(argc, argv);
    if (o.help) {
      out << (command == "map" ? kMapHelp : kQueryHelp);
      return 0;
    }
    return command == "map" ? run_map(o, out) : run_query(o, out);
  } catch (const CliError& e) {
    err << "ccmap: error: " << e.message << "\n";
    return e.code;
  } catch (const std::bad_alloc&) {
    err << "ccmap: error: out of memory\n";
    return 1;
  } catch (const std::exception& e) {
    err << "ccmap: error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace ccmap::tools
