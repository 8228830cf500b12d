#include "cli.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <system_error>
#include <vector>

#include "cloud_reader.hpp"
#include "csv_writer.hpp"
#include "layer_images.hpp"
#include "map_runner.hpp"
#include "png.hpp"

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
    "\n"
    "  --preset NAME   cadre: 4 cm piece-wise constant Kalman layer, then 8/16/32/64 cm CCM layers\n"
    "                  ccm, kf, omg: one 256 x 256 layer of CCM, Kalman or OMG cells\n"
    "  --res METRES    finest cell width (default 0.04 for cadre, 0.08 otherwise); the layers of\n"
    "                  cadre keep their 1:2:4:8:16 ratios\n"
    "  --wl W_L        weight limit W_l of CCM and OMG cells (default 1000)\n"
    "  --cloud FILE    one frame, map-frame coordinates: .ply (ascii/binary), .las (1.0-1.4,\n"
    "                  uncompressed) or text 'x y z [w]' per line; repeat for more frames,\n"
    "                  applied in order. A per-point weight (PLY property, 4th text column)\n"
    "                  replaces the sensor model's weight for CCM and OMG cells (Kalman cells\n"
    "                  weigh by range variance); weights <= 0 or non-finite are counted as bad.\n"
    "  --poses FILE    one line 'x y z yaw' per frame: the sensor position in the map frame; the\n"
    "                  map is re-centred on (x, y) before the frame. Without it the map stays\n"
    "                  centred on the first cloud's centroid.\n"
    "  --sensor NAME   lidar (default): constant range noise --sigma (default 0.005 m);\n"
    "                  stereo: the CADRE stereo model (noise grows with range^2 from the pose)\n"
    "  --out DIR       writes DIR/layer_<k>.csv (finest first) and layer_<k>_{height,slope,\n"
    "                  normal_var,class}.png; class colours: unknown grey, traversable green,\n"
    "                  obstacle red, steep orange, unobserved black\n"
    "  --costmap       also writes DIR/costmap_<k>.png and .pgm per layer: the planner's cost\n"
    "                  raster (costmap_2d values as grey levels: 0 free .. 252 cost, 253\n"
    "                  inscribed, 254 lethal, 255 unknown) over layer k's window at its cell\n"
    "                  width, north up; each pixel the worst of the map over its square\n"
    "  --inflate M     with --costmap: pixels within M metres of a lethal one are inscribed\n"
    "\n"
    "Coordinates may be absolute (e.g. UTM): the tool subtracts a local origin (the first\n"
    "cloud's centroid rounded to the coarsest cell width) in double precision before the\n"
    "float library sees them, and adds it back to every output coordinate and height.\n";

constexpr const char* kQueryHelp =
    "usage: ccmap query --preset NAME --cloud FILE [--cloud FILE ...] --at X,Y\n"
    "                   [--footprint LENGTH,WIDTH[,YAW_DEG]] [--max-unknown-share F]\n"
    "       ccmap query --preset NAME --cloud FILE [--cloud FILE ...] --path X1,Y1:X2,Y2[:...]\n"
    "                   --footprint LENGTH,WIDTH [--step METRES] [--max-unknown-share F]\n"
    "                   [--res METRES] [--wl W_L] [--poses FILE] [--sensor lidar|stereo] [--sigma METRES]\n"
    "\n"
    "Maps the clouds as 'ccmap map' does (same options, see 'ccmap map --help') and prints the\n"
    "map's answer at the map-frame point (X, Y): layer, height, slopes, inclination, normal\n"
    "variance, elevation variance and class, one 'key: value' per line.\n"
    "\n"
    "  --footprint L,W[,YAW_DEG]  with --at: also the rover body, an L x W m rectangle centred\n"
    "                  there, its length along YAW_DEG (degrees from +x, default 0): adds\n"
    "                  footprint_class (traversable|obstacle|steep|unknown), footprint_unknown_share,\n"
    "                  footprint_max_step_m, footprint_max_inclination_deg\n"
    "  --path X1,Y1:X2,Y2[:...]  the body swept along this polyline (map frame, 2 .. 256 points),\n"
    "                  its length along each segment: prints first_hazard_m (obstacle or steep)\n"
    "                  and first_unknown_m, each a distance along the path or 'none'\n"
    "  --step M        distance between the body's poses along --path (default: the finest cell)\n"
    "  --max-unknown-share F  a footprint with a larger unknown share is unknown (default 0.1)\n";

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
  bool help = false;
  bool have_footprint = false;
  double footprint_length = 0.0, footprint_width = 0.0, footprint_yaw_deg = 0.0;
  bool footprint_has_yaw = false;
  std::vector<double> path;  ///< x0 y0 x1 y1 ... (map frame, as given)
  double step = 0.0;         ///< <= 0: the finest cell width
  double max_unknown_share = 0.1;
  bool costmap = false;
  double inflate = 0.0;
};

/// "A,B[,C]" -> numbers; `what` names the option in errors.
std::vector<double> parse_list(const std::string& flag, const std::string& text, char separator) {
  std::vector<double> out;
  std::size_t start = 0;
  while (true) {
    const std::size_t end = text.find(separator, start);
    out.push_back(parse_number(flag, text.substr(start, end == std::string::npos ? std::string::npos : end - start)));
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return out;
}

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
    if (arg == "--costmap") {
      o.costmap = true;
      continue;
    }
    if (arg.rfind("--", 0) != 0) fail("unexpected argument '" + arg + "' (options start with --)", 2);
    const std::size_t eq = arg.find('=');
    if (eq != std::string::npos) {
      value = arg.substr(eq + 1);
      arg = arg.substr(0, eq);
      have_value = true;
    }
    static const char* kKnown[] = {"--preset", "--res",  "--wl",        "--cloud", "--poses",
                                   "--out",    "--at",   "--sensor",    "--sigma", "--footprint",
                                   "--path",   "--step", "--max-unknown-share", "--inflate"};
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
    } else if (arg == "--footprint") {
      const std::vector<double> v = parse_list(arg, value, ',');
      if (v.size() < 2 || v.size() > 3) fail("--footprint: expected LENGTH,WIDTH[,YAW_DEG], got '" + value + "'", 2);
      for (std::size_t k = 0; k < v.size(); ++k) {
        if (!std::isfinite(v[k]) || (k < 2 && !(v[k] > 0.0))) {
          fail("--footprint: '" + value + "': length and width must be > 0, all finite", 2);
        }
      }
      o.footprint_length = v[0];
      o.footprint_width = v[1];
      o.footprint_has_yaw = v.size() == 3;
      o.footprint_yaw_deg = o.footprint_has_yaw ? v[2] : 0.0;
      o.have_footprint = true;
    } else if (arg == "--path") {
      o.path.clear();
      std::size_t start = 0;
      while (true) {
        const std::size_t end = value.find(':', start);
        const std::string point = value.substr(start, end == std::string::npos ? std::string::npos : end - start);
        const std::vector<double> xy = parse_list(arg, point, ',');
        if (xy.size() != 2 || !std::isfinite(xy[0]) || !std::isfinite(xy[1])) {
          fail("--path: expected X1,Y1:X2,Y2[:...] (finite), got '" + point + "'", 2);
        }
        o.path.insert(o.path.end(), xy.begin(), xy.end());
        if (end == std::string::npos) break;
        start = end + 1;
      }
      if (o.path.size() < 4) fail("--path: at least two points X1,Y1:X2,Y2", 2);
    } else if (arg == "--step") {
      o.step = parse_positive(arg, value, 100.0);
    } else if (arg == "--max-unknown-share") {
      o.max_unknown_share = parse_number(arg, value);
      if (!(o.max_unknown_share >= 0.0 && o.max_unknown_share <= 1.0)) {
        fail("--max-unknown-share: " + value + " is out of range (expected 0 .. 1)", 2);
      }
    } else if (arg == "--inflate") {
      o.inflate = parse_number(arg, value);
      if (!(o.inflate >= 0.0) || !std::isfinite(o.inflate)) fail("--inflate: " + value + " is out of range (expected >= 0)", 2);
    }
  }
  return o;
}

std::string base_name(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

/// A mapped sequence: the runner, the local origin and the per-frame accounting.
struct MappedClouds {
  std::unique_ptr<MapRunner> runner;
  double origin[3] = {0.0, 0.0, 0.0};  ///< map-frame position of the local origin (m)
  std::int64_t origin_cells[3] = {0, 0, 0};  ///< origin / coarsest cell width (exact integers)
  double coarsest_width = 0.0;
  std::vector<double> widths;          ///< requested cell width per layer (m), finest first
  FrameStats totals;
  std::uint64_t read = 0, reader_non_finite = 0;
};

const char* sensor_name(const Options& o) {
  return o.sensor == SensorChoice::kLidar ? "lidar" : "stereo (CADRE model)";
}

MappedClouds build_map(const Options& o, std::ostream& out, bool verbose) {
  if (o.preset.empty()) fail("--preset is required (cadre, ccm, kf or omg)", 2);
  std::string error;
  MappedClouds m;
  m.runner = make_map_runner(o.preset, &error);
  if (!m.runner) fail(error, 2);
  if (o.clouds.empty()) fail("at least one --cloud FILE is required", 2);

  const int layers = preset_layer_count(o.preset);
  const double finest = o.res > 0.0 ? o.res : preset_default_cell_width(o.preset);
  for (int k = 0; k < layers; ++k) m.widths.push_back(finest * std::ldexp(1.0, k));
  m.coarsest_width = m.widths.back();

  RunnerOptions ro;
  ro.preset = o.preset;
  ro.finest_cell_width_m = finest;
  ro.weight_limit = o.wl;
  ro.sensor = o.sensor;
  ro.lidar_sigma_m = o.sigma;
  if (!m.runner->init(ro, &error)) fail(error);

  std::vector<Pose> poses;
  if (!o.poses.empty()) {
    if (!read_poses(o.poses, &poses, &error)) fail(error);
    if (poses.size() != o.clouds.size()) {
      fail(o.poses + ": " + std::to_string(poses.size()) + " poses for " + std::to_string(o.clouds.size()) +
           " clouds (one line per --cloud expected)");
    }
  }

  std::vector<float> xyz;

  std::vector<float> weights;
  for (std::size_t f = 0; f < o.clouds.size(); ++f) {
    const Cloud cloud = read_cloud(o.clouds[f]);
    if (!cloud.ok()) fail(cloud.error);
    if (cloud.size() == 0) {
      fail(o.clouds[f] + ": empty cloud (" + std::to_string(cloud.declared) + " points, " +
           std::to_string(cloud.skipped_non_finite) + " of them non-finite)");
    }
    m.read += cloud.declared;
    m.reader_non_finite += cloud.skipped_non_finite;
    if (f == 0) {
      // Local origin: the centroid (double), rounded to the coarsest cell width so that every
      // layer's cell grid stays aligned with whole map-frame cells.
      double sum[3] = {0.0, 0.0, 0.0};
      const std::vector<double>* axes[3] = {&cloud.x, &cloud.y, &cloud.z};
      for (int a = 0; a < 3; ++a) {
        for (double v : *axes[a]) sum[a] += v;
        const double centroid = sum[a] / static_cast<double>(cloud.size());
        m.origin_cells[a] = std::llround(centroid / m.coarsest_width);
        m.origin[a] = static_cast<double>(m.origin_cells[a]) * m.coarsest_width;
      }
      if (verbose) {
        out << "ccmap " << o.command << ": preset " << o.preset << ", " << layers << " layer(s), cell widths";
        for (double w : m.widths) out << ' ' << fmt("%g", w);
        out << " m, W_l " << fmt("%g", m.runner->weight_limit()) << ", min weight "
            << fmt("%g", m.runner->min_weight()) << ", sensor " << sensor_name(o);
        if (o.sensor == SensorChoice::kLidar) out << " (sigma " << fmt("%g", o.sigma) << " m)";
        out << "\n";
        out << "origin (map frame): " << fmt("%.3f", m.origin[0]) << ' ' << fmt("%.3f", m.origin[1]) << ' '
            << fmt("%.3f", m.origin[2]) << "  (first cloud's centroid rounded to " << fmt("%g", m.coarsest_width)
            << " m)\n";
      }
    }
    // Pose: re-centre, and the sensor origin for the noise model (local frame).
    float sensor[3] = {0.0F, 0.0F, 0.0F};
    if (!poses.empty()) {
      const Pose& p = poses[f];
      sensor[0] = static_cast<float>(p.x - m.origin[0]);
      sensor[1] = static_cast<float>(p.y - m.origin[1]);
      sensor[2] = static_cast<float>(p.z - m.origin[2]);
      if (!m.runner->move_to(sensor[0], sensor[1], &error)) {
        fail(o.poses + ": pose " + std::to_string(f + 1) + ": " + error + "; is it in the clouds' frame?");
      }
    } else if (f == 0) {
      if (!m.runner->move_to(0.0F, 0.0F, &error)) fail(error);
    }
    xyz.resize(3U * cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      // Subtract the origin in double, then round to float.
      xyz[3 * i] = static_cast<float>(cloud.x[i] - m.origin[0]);
      xyz[3 * i + 1] = static_cast<float>(cloud.y[i] - m.origin[1]);
      xyz[3 * i + 2] = static_cast<float>(cloud.z[i] - m.origin[2]);
    }
    weights.clear();
    if (cloud.has_weight) {
      weights.reserve(cloud.size());
      for (std::size_t i = 0; i < cloud.size(); ++i) weights.push_back(static_cast<float>(cloud.w[i]));
    }
    FrameStats stats;
    const auto t0 = std::chrono::steady_clock::now();
    if (!m.runner->update_frame(xyz, weights, sensor, &stats, &error)) fail(o.clouds[f] + ": " + error);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    stats.rejected_non_finite += cloud.skipped_non_finite;
    stats.received += cloud.skipped_non_finite;
    m.totals.add(stats);
    if (verbose) {
      out << "frame " << (f + 1) << ": " << base_name(o.clouds[f]) << " [" << cloud.format << "]: " << cloud.declared
          << " points, used " << stats.used << ", rejected: non-finite " << stats.rejected_non_finite
          << ", out of range " << stats.rejected_out_of_range << ", bad weight " << stats.rejected_weight
          << ", outside map " << stats.outside_map << ", too noisy " << stats.too_noisy << "; "
          << fmt("%.1f", ms) << " ms\n";
      if (cloud.has_weight) {
        out << "note: " << base_name(o.clouds[f]) << ": per-point weights from the file replace the sensor model's\n";
      }
    }
  }
  if (verbose) {
    const FrameStats& t = m.totals;
    out << "points: read " << m.read << ", used " << t.used << ", rejected: non-finite " << t.rejected_non_finite
        << ", out of range " << t.rejected_out_of_range << ", bad weight " << t.rejected_weight << ", outside map "
        << t.outside_map << ", too noisy " << t.too_noisy << "\n";
  }
  return m;
}

/// Layer rows in the map frame (origin added back in double).
std::vector<LayerCellRow> layer_rows(const MappedClouds& m, int layer, const std::vector<LocalCell>& cells) {
  const double res = m.widths[static_cast<std::size_t>(layer)];
  const std::int64_t scale = std::int64_t{1} << (static_cast<int>(m.widths.size()) - 1 - layer);
  std::vector<LayerCellRow> rows;
  rows.reserve(cells.size());
  for (const LocalCell& c : cells) {
    LayerCellRow r;
    r.layer = layer;
    r.ix = static_cast<std::int64_t>(c.ix) + m.origin_cells[0] * scale;
    r.iy = static_cast<std::int64_t>(c.iy) + m.origin_cells[1] * scale;
    r.cx = (static_cast<double>(r.ix) + 0.5) * res;
    r.cy = (static_cast<double>(r.iy) + 0.5) * res;
    r.res = res;
    r.weight = c.weight;
    r.height = static_cast<double>(c.height) + m.origin[2];
    r.slope_x = c.slope_x;
    r.slope_y = c.slope_y;
    r.normal_var = c.normal_variance;
    r.elev_var = c.elevation_variance;
    r.cell_class = c.cell_class;
    rows.push_back(std::move(r));
  }
  return rows;
}

/// Writes a cost raster (row 0 at the lowest y) as a binary PGM and a grey PNG, north up.
void write_costmap_images(const std::string& prefix, const std::vector<std::uint8_t>& cost, int side) {
  std::string error;
  RgbImage image(side, side);
  std::vector<unsigned char> rows;
  rows.reserve(cost.size());
  for (int row = 0; row < side; ++row) {
    const int iy = side - 1 - row;  // north up
    for (int ix = 0; ix < side; ++ix) {
      const std::uint8_t v = cost[static_cast<std::size_t>(iy) * static_cast<std::size_t>(side) + static_cast<std::size_t>(ix)];
      const std::uint8_t grey[3] = {v, v, v};
      image.set(ix, row, grey);
      rows.push_back(v);
    }
  }
  if (!write_png(prefix + ".png", image, &error)) fail(error);
  std::ofstream pgm(prefix + ".pgm", std::ios::binary);
  pgm << "P5\n" << side << ' ' << side << "\n255\n";
  pgm.write(reinterpret_cast<const char*>(rows.data()), static_cast<std::streamsize>(rows.size()));
  if (!pgm) fail("cannot write " + prefix + ".pgm");
}

int run_map(const Options& o, std::ostream& out) {
  if (o.out_dir.empty()) fail("--out DIR is required", 2);
  if (o.have_at) fail("--at belongs to 'ccmap query'", 2);
  if (o.have_footprint || !o.path.empty()) fail("--footprint and --path belong to 'ccmap query'", 2);
  if (o.inflate > 0.0 && !o.costmap) fail("--inflate needs --costmap", 2);
  MappedClouds m = build_map(o, out, true);
  std::error_code ec;
  std::filesystem::create_directories(o.out_dir, ec);
  if (ec || !std::filesystem::is_directory(o.out_dir)) {
    fail("cannot create output directory '" + o.out_dir + "'" + (ec ? ": " + ec.message() : std::string()));
  }
  std::string error;
  for (int k = 0; k < m.runner->layer_count(); ++k) {
    std::vector<LocalCell> cells;
    if (!m.runner->export_layer(k, &cells, &error)) fail(error);
    const std::vector<LayerCellRow> rows = layer_rows(m, k, cells);
    const std::string prefix = o.out_dir + "/layer_" + std::to_string(k);
    if (!write_layer_csv(prefix + ".csv", rows, &error)) fail(error);
    // Pictures show the bounding box of the observed cells (a small scan in a large layer
    // would otherwise be a speck); a layer with no observed cell is drawn whole, black.
    LayerWindow window{};
    if (rows.empty()) {
      std::int32_t wx = 0, wy = 0;
      m.runner->layer_window_min(k, &wx, &wy);
      const std::int64_t scale = std::int64_t{1} << (static_cast<int>(m.widths.size()) - 1 - k);
      window = LayerWindow{wx + m.origin_cells[0] * scale, wy + m.origin_cells[1] * scale, m.runner->layer_side(k),
                           m.runner->layer_side(k)};
    }
    if (!write_layer_images(prefix, rows, window, &error)) fail(error);
    std::size_t counts[4] = {0, 0, 0, 0};
    for (const LayerCellRow& r : rows) {
      if (r.cell_class == "traversable") ++counts[1];
      else if (r.cell_class == "obstacle") ++counts[2];
      else if (r.cell_class == "steep") ++counts[3];
      else ++counts[0];
    }
    const int side = m.runner->layer_side(k);
    out << "layer " << k << " (" << fmt("%g", m.widths[static_cast<std::size_t>(k)]) << " m, " << side << " x "
        << side << ", " << (m.runner->layer_is_ccm(k) ? "CCM" : (o.preset == "omg" ? "OMG" : "Kalman"))
        << "): " << (rows.size() - counts[0]) << " cells known of " << rows.size() << " observed (traversable "
        << counts[1] << ", obstacle " << counts[2] << ", steep " << counts[3] << ", unknown " << counts[0]
        << ") -> " << prefix << ".csv\n";
  }
  out << "pictures: " << o.out_dir << "/layer_<k>_{height,slope,normal_var,class}.png, north up, observed area"
      << " (class: unknown grey, traversable green, obstacle red, steep orange; unobserved black)\n";
  if (o.costmap) {
    for (int k = 0; k < m.runner->layer_count(); ++k) {
      const int side = m.runner->layer_side(k);
      const float res = m.runner->layer_cell_width(k);
      float cx = 0.0F, cy = 0.0F;
      m.runner->layer_window_centre(k, &cx, &cy);
      std::vector<std::uint8_t> cost;
      if (!m.runner->costmap(cx, cy, res, side, static_cast<float>(o.inflate), &cost, &error)) fail(error);
      const std::string prefix = o.out_dir + "/costmap_" + std::to_string(k);
      write_costmap_images(prefix, cost, side);
      std::size_t counts[4] = {0, 0, 0, 0};  // free/cost, inscribed, lethal, unknown
      for (const std::uint8_t v : cost) ++counts[v <= 252 ? 0 : v - 252];
      out << "costmap " << k << " (" << side << " x " << side << " at " << fmt("%g", m.widths[static_cast<std::size_t>(k)])
          << " m, centre " << fmt("%.3f", static_cast<double>(cx) + m.origin[0]) << ' '
          << fmt("%.3f", static_cast<double>(cy) + m.origin[1]) << "): cost " << counts[0] << ", inscribed "
          << counts[1] << ", lethal " << counts[2] << ", unknown " << counts[3] << " pixels -> " << prefix
          << ".{png,pgm}\n";
    }
  }
  return 0;
}

/// The path query: first_hazard_m / first_unknown_m lines.
int run_path_query(const Options& o, const MappedClouds& m, std::ostream& out) {
  if (!o.have_footprint) fail("--path needs --footprint LENGTH,WIDTH (the body swept along it)", 2);
  if (o.footprint_has_yaw) fail("--footprint: YAW_DEG does not apply to --path (the body follows the path)", 2);
  std::vector<float> xy;
  for (std::size_t i = 0; i < o.path.size(); i += 2) {
    xy.push_back(static_cast<float>(o.path[i] - m.origin[0]));
    xy.push_back(static_cast<float>(o.path[i + 1] - m.origin[1]));
  }
  const double step = o.step > 0.0 ? o.step : m.widths.front();
  const LocalPath p = m.runner->path(xy, static_cast<float>(o.footprint_length), static_cast<float>(o.footprint_width),
                                     static_cast<float>(step), static_cast<float>(o.max_unknown_share));
  if (p.status != "ok") fail("the map refused the path query (" + p.status + ")", 2);
  out << "path_length_m: " << fmt("%.6f", p.length_m) << "\n";
  out << "path_poses: " << p.poses << "\n";
  out << "first_hazard_m: " << (p.hazard ? fmt("%.6f", p.first_hazard_m) : std::string("none")) << "\n";
  if (p.hazard) {
    out << "hazard_class: " << p.hazard_class << "\n";
    out << "hazard_x: " << fmt("%.6f", static_cast<double>(p.hazard_x) + m.origin[0]) << "\n";
    out << "hazard_y: " << fmt("%.6f", static_cast<double>(p.hazard_y) + m.origin[1]) << "\n";
  }
  out << "first_unknown_m: " << (p.unknown ? fmt("%.6f", p.first_unknown_m) : std::string("none")) << "\n";
  return 0;
}

int run_query(const Options& o, std::ostream& out) {
  if (!o.have_at && o.path.empty()) fail("--at X,Y or --path X1,Y1:X2,Y2[:...] is required", 2);
  if (o.have_at && !o.path.empty()) fail("--at and --path are two queries: give one", 2);
  if (!o.out_dir.empty()) fail("--out belongs to 'ccmap map'", 2);
  if (o.costmap || o.inflate > 0.0) fail("--costmap and --inflate belong to 'ccmap map'", 2);
  if (o.step > 0.0 && o.path.empty()) fail("--step belongs to --path", 2);
  std::ostringstream log;
  MappedClouds m = build_map(o, log, true);
  if (!o.path.empty()) return run_path_query(o, m, out);
  const double lx = o.at_x - m.origin[0], ly = o.at_y - m.origin[1];
  const LocalQuery q = m.runner->query(static_cast<float>(lx), static_cast<float>(ly));
  const double kPi = 3.14159265358979323846;
  out << "x: " << fmt("%.6f", o.at_x) << "\n";
  out << "y: " << fmt("%.6f", o.at_y) << "\n";
  out << "status: " << q.status << "\n";
  out << "layer: " << q.layer << "\n";
  const bool layer_ok = q.layer >= 0 && q.layer < static_cast<int>(m.widths.size());
  out << "cell_width_m: " << fmt("%g", layer_ok ? m.widths[static_cast<std::size_t>(q.layer)] : 0.0)
      << "\n";
  const bool ok = q.status == "ok";
  out << "height_m: " << (ok ? fmt("%.6f", static_cast<double>(q.height) + m.origin[2]) : std::string("nan")) << "\n";
  out << "slope_x: " << fmt("%.6g", q.slope_x) << "\n";
  out << "slope_y: " << fmt("%.6g", q.slope_y) << "\n";
  out << "inclination: " << fmt("%.6g", q.inclination) << "\n";
  out << "inclination_deg: " << fmt("%.3f", std::atan(static_cast<double>(q.inclination)) * 180.0 / kPi) << "\n";
  out << "normal_variance_m2: " << fmt("%.6g", q.normal_variance) << "\n";
  out << "elevation_variance_m2: " << fmt("%.6g", q.elevation_variance) << "\n";
  out << "weight: " << fmt("%.6g", q.weight) << "\n";
  out << "class: " << q.cell_class << "\n";
  if (o.have_footprint) {
    const double yaw = o.footprint_yaw_deg * kPi / 180.0;
    const LocalFootprint f = m.runner->footprint(
        static_cast<float>(lx), static_cast<float>(ly), static_cast<float>(std::cos(yaw)), static_cast<float>(std::sin(yaw)),
        static_cast<float>(o.footprint_length), static_cast<float>(o.footprint_width), static_cast<float>(o.max_unknown_share));
    if (f.status != "ok" && f.status != "outside_map") fail("the map refused the footprint (" + f.status + ")", 2);
    out << "footprint_class: " << f.verdict << "\n";
    out << "footprint_unknown_share: " << fmt("%.6f", f.unknown_share) << "\n";
    out << "footprint_max_step_m: " << fmt("%.6f", f.max_step) << "\n";
    out << "footprint_max_inclination_deg: "
        << fmt("%.3f", std::atan(static_cast<double>(f.max_inclination)) * 180.0 / kPi) << "\n";
  }
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
