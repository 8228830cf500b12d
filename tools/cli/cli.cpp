#include "cli.hpp"

#include <algorithm>
#include <functional>
#include <utility>
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

#include <CLI/CLI.hpp>

#include "ccmap/cell/ccm_cell.hpp"
#include "cloud_reader.hpp"
#include "csv_writer.hpp"
#include "layer_images.hpp"
#include "ccmap/planner/costmap.hpp"
#include "map_runner.hpp"
#include "origin.hpp"
#include "png.hpp"
#include "raster_io.hpp"
#include "product_view.hpp"
#include "saved_map.hpp"
#include "tiling.hpp"

namespace ccmap::tools {
namespace {

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

/// "X,Y" into two finite numbers.
void parse_pair(const std::string& flag, const std::string& value, double* x, double* y) {
  const std::size_t comma = value.find(',');
  if (comma == std::string::npos) fail(flag + ": expected X,Y, got '" + value + "'", 2);
  *x = parse_number(flag, value.substr(0, comma));
  *y = parse_number(flag, value.substr(comma + 1));
  if (!std::isfinite(*x) || !std::isfinite(*y)) fail(flag + ": coordinates must be finite", 2);
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
  double gate = 0.0;  ///< outlier gate, standard deviations; 0 = off
  std::vector<std::string> clouds;  ///< the frames in order: cloud files and --dem rasters
  std::vector<bool> dem;             ///< per frame: a raster DEM (--dem), else a cloud file
  std::string poses;
  std::string out_dir;
  std::string save;
  std::vector<std::string> inputs;
  bool have_offset = false;
  double offset_x = 0.0, offset_y = 0.0;
  bool have_at = false;
  double at_x = 0.0, at_y = 0.0;
  SensorChoice sensor = SensorChoice::kLidar;
  double sigma = 0.005;
  AreaBounds bounds;
  bool have_footprint = false;
  double footprint_length = 0.0, footprint_width = 0.0, footprint_yaw_deg = 0.0;
  bool footprint_has_yaw = false;
  std::vector<double> path;  ///< x0 y0 x1 y1 ... (map frame, as given)
  double step = 0.0;         ///< <= 0: the finest cell width
  double max_unknown_share = 0.1;
  bool costmap = false;
  double inflate = 0.0;
  bool paper_cell = false;  ///< --paper-cell: the paper's 9-float CCM cells (PaperCell<Config>)
  bool geotiff = false;  ///< --geotiff: DIR/layer_<k>.tif too
  bool register_frames = false;  ///< map --register: each frame after the first registered before it is folded
  bool align = false;            ///< merge --align: each map aligned with the first before it is merged
  int epsg = 0;          ///< --epsg CODE; 0: none given
  std::string product_in;   ///< product --in FILE
  std::string product_png;  ///< product --png PREFIX
  bool product_cells = false;  ///< product --cells
  /// A planner query (--footprint or --path) without --poses: a map centred on it, not tiles.
  [[nodiscard]] bool centred_map() const { return (have_footprint || !path.empty()) && poses.empty(); }
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

/// --path X1,Y1:X2,Y2[:...]: two or more finite points, x0 y0 x1 y1 ...
std::vector<double> parse_path(const std::string& value) {
  std::vector<double> path;
  std::size_t start = 0;
  while (true) {
    const std::size_t end = value.find(':', start);
    const std::string point = value.substr(start, end == std::string::npos ? std::string::npos : end - start);
    const std::vector<double> xy = parse_list("--path", point, ',');
    if (xy.size() != 2 || !std::isfinite(xy[0]) || !std::isfinite(xy[1])) {
      fail("--path: expected X1,Y1:X2,Y2[:...] (finite), got '" + point + "'", 2);
    }
    path.insert(path.end(), xy.begin(), xy.end());
    if (end == std::string::npos) break;
    start = end + 1;
  }
  if (path.size() < 4) fail("--path: at least two points X1,Y1:X2,Y2", 2);
  return path;
}

// --- the command line (CLI11) -------------------------------------------------------------
// CLI11 owns the structure: subcommands, which option belongs where, required options, options
// that need or exclude others, duplicates, and the generated --help. The value formats (X,Y,
// bounds, paths, ranges) stay with the parse_* functions above, whose messages name the option.

/// The explanatory paragraphs of each command's --help (after the generated option list).
constexpr const char* kMapFooter =
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
    "from the origin on an axis, are counted as out of range.";

constexpr const char* kQueryFooter =
    "Maps the clouds as 'ccmap map' does (same options, see 'ccmap map --help') and prints the\n"
    "map's answer at the map-frame point (X, Y): layer, height, slopes, inclination, normal\n"
    "variance, elevation variance, class and upset (1: unknown because the cell failed its check),\n"
    "one 'key: value' per line. Without --poses only the\n"
    "tile that holds (X, Y) is mapped (the answer is the whole map's); a point whose tile holds no\n"
    "point of the clouds is outside the map (status: outside_map).\n"
    "\n"
    "With --footprint (or --path) and without --poses the clouds are not tiled: the stack is\n"
    "centred on the footprint's centre (the path's first point) and every cloud folded into it as\n"
    "one frame, as a rover standing there would map the ground; points beyond its windows count\n"
    "as outside map, and the point answer of --at comes from the same map. With --poses the\n"
    "queries read the map at the last pose.";

constexpr const char* kMergeFooter =
    "Merges maps of the same preset and cell width: each --in is a map saved by 'ccmap map --save'\n"
    "or a snapshot written by flight software (save_snapshot; its origin is then 0). The result\n"
    "holds the first map's parameters and windows; the cells of the others are merged exactly\n"
    "(CCM cells as sufficient statistics, Kalman cells in information form, docs/design.md) where\n"
    "they fall in those windows, and counted as outside otherwise. Writes the same CSV files and\n"
    "pictures as 'ccmap map', in absolute coordinates (the first map's origin added back).";

/// An option whose value text goes to `parse` (which may fail with the option's message).
CLI::Option* add_value(CLI::App* app, const std::string& name, const std::string& type, const std::string& help,
                       std::function<void(const std::string&)> parse) {
  return app->add_option_function<std::string>(name, std::move(parse), help)->type_name(type);
}

/// An option naming a file or directory: an empty value is refused ("--out needs a directory").
CLI::Option* add_name(CLI::App* app, const std::string& name, const std::string& type, const std::string& what,
                      const std::string& help, std::string* target) {
  return add_value(app, name, type, help, [name, what, target](const std::string& v) {
    if (v.empty()) fail(name + " needs " + what, 2);
    *target = v;
  });
}

/// A repeatable option: `parse` runs for every occurrence as it is parsed, so that repeated
/// options (and --cloud / --dem between them) keep their command-line order.
CLI::Option* add_repeated(CLI::App* app, const std::string& name, const std::string& type, const std::string& help,
                          std::function<void(const std::string&)> parse) {
  return add_value(app, name, type, help, std::move(parse))
      ->trigger_on_parse()
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
}

/// --cloud FILE or --dem FILE: one more frame.
void add_frame_option(CLI::App* app, Options& o, const std::string& name, bool dem, const std::string& help) {
  add_repeated(app, name, "FILE", help, [&o, name, dem](const std::string& v) {
    if (v.empty()) fail(name + " needs a file name", 2);
    o.clouds.push_back(v);
    o.dem.push_back(dem);
  });
}

/// --paper-cell: 'ccmap map', 'ccmap query' and 'ccmap merge' (a paper-cell map merges only
/// with paper-cell maps: another cell kind is another snapshot shape).
void add_paper_cell_option(CLI::App* app, Options& o) {
  app->add_flag("--paper-cell", o.paper_cell,
                "CCM cells of the paper's 9 floats (slopes per axis, eq. 9; coverage per\n"
                "axis, eq. 12) instead of the full cell with the lateral covariance (the\n"
                "least-squares plane; coverage by the smaller eigenvalue); cadre and ccm only");
}

/// --preset, the frames and the mapping parameters: 'ccmap map' and 'ccmap query'.
void add_mapping_options(CLI::App* app, Options& o) {
  add_value(app, "--preset", "NAME",
            "cadre: 4 cm piece-wise constant Kalman layer, then 8/16/32/64 cm CCM layers\n"
            "ccm, kf, omg: one 256 x 256 layer of CCM, Kalman or OMG cells",
            [&o](const std::string& v) { o.preset = v; })
      ->required();
  add_paper_cell_option(app, o);
  add_value(app, "--res", "METRES",
            "finest cell width (default 0.04 for cadre, 0.08 otherwise); the layers of\n"
            "cadre keep their 1:2:4:8:16 ratios",
            [&o](const std::string& v) { o.res = parse_positive("--res", v, 100.0); });
  add_value(app, "--wl", "W_L", "weight limit W_l of CCM and OMG cells (default 1000)",
            [&o](const std::string& v) { o.wl = parse_positive("--wl", v, 1e30, /*allow_inf=*/true); });
  add_value(app, "--gate", "K",
            "the library's outlier gate at K standard deviations (1..100) with its change\n"
            "rule (docs/design.md section 9); default 0: off, every point trusted. Each\n"
            "file is one frame and a frame judges at most 512 cells per pool: held points\n"
            "beyond that are dropped (counted)",
            [&o](const std::string& v) {
              o.gate = parse_number("--gate", v);
              const bool off = o.gate >= 0.0 && o.gate <= 0.0;  // exactly 0 (no float ==)
              if (!off && !(o.gate >= 1.0 && o.gate <= 100.0)) {
                fail("--gate: " + v + " is out of range (expected 0 or a number in 1..100)", 2);
              }
            });
  add_frame_option(app, o, "--cloud", false,
            "one frame, map-frame coordinates: .ply (ascii/binary), .las (1.0-1.4,\n"
            "uncompressed) or text 'x y z [w]' per line; repeat for more frames,\n"
            "applied in order. A per-point weight (PLY property, 4th text column)\n"
            "replaces the sensor model's weight for CCM and OMG cells (Kalman cells\n"
            "weigh by range variance); weights <= 0 or non-finite are counted as bad.");
  add_frame_option(app, o, "--dem", true,
            "one frame from a raster DEM (GeoTIFF, ESRI ASCII grid, anything GDAL reads):\n"
            "one point per cell with data, at the cell centre; no-data cells skipped.\n"
            "Choose --res of a few DEM cells (a cell needs min-weight points to be known)");
  add_value(app, "--poses", "FILE",
            "one line 'x y z yaw' per frame: the sensor position in the map frame; the\n"
            "map is re-centred on (x, y) before the frame and follows the poses like a\n"
            "rover's map: points beyond its windows count as outside map.",
            [&o](const std::string& v) { o.poses = v; });
  add_value(app, "--sensor", "lidar|stereo",
            "lidar (default): constant range noise --sigma (default 0.005 m);\n"
            "stereo: the CADRE stereo model (noise grows with range^2 from the pose;\n"
            "without --poses, from the local origin)",
            [&o](const std::string& v) {
              if (v == "lidar") o.sensor = SensorChoice::kLidar;
              else if (v == "stereo") o.sensor = SensorChoice::kCadreStereo;
              else fail("--sensor: unknown sensor '" + v + "' (expected lidar or stereo)", 2);
            });
  add_value(app, "--sigma", "METRES", "lidar range noise (default 0.005 m)",
            [&o](const std::string& v) { o.sigma = parse_positive("--sigma", v, 10.0); });
  add_value(app, "--bounds", "XMIN,YMIN,XMAX,YMAX",
            "map only the points inside this map-frame rectangle (absolute coordinates,\n"
            "edges included); the others count as outside map",
            [&o](const std::string& v) { o.bounds = parse_bounds(v); });
}

/// --out, --geotiff, --epsg: the outputs of 'ccmap map' and 'ccmap merge'.
void add_output_options(CLI::App* app, Options& o) {
  add_name(app, "--out", "DIR", "a directory",
           "writes DIR/layer_<k>.csv (finest first) and layer_<k>_{height,slope,\n"
           "normal_var,class}.png; class colours: unknown grey, traversable green,\n"
           "obstacle red, steep orange, drop purple, unobserved black",
           &o.out_dir)
      ->required();
  CLI::Option* geotiff = app->add_flag("--geotiff", o.geotiff,
                                       "also writes DIR/layer_<k>.tif per layer (GDAL): the pictures' area, one pixel\n"
                                       "per cell in absolute coordinates; Float64 bands height, slope_x, slope_y,\n"
                                       "normal_var, class (0 unknown, 1 traversable, 2 obstacle, 3 steep, 4 drop),\n"
                                       "NaN where unobserved");
  add_value(app, "--epsg", "CODE",
            "with --geotiff: the coordinate system written (default: the first --dem's, if\n"
            "it has one, else none)",
            [&o](const std::string& v) {
              const double code = parse_number("--epsg", v);
              if (!(code >= 1.0 && code <= 999999.0) || code != std::floor(code)) {
                fail("--epsg: " + v + " is not an EPSG code (expected a whole number 1 .. 999999)", 2);
              }
              o.epsg = static_cast<int>(code);
            })
      ->needs(geotiff);
}

void add_map_command(CLI::App& app, Options& o) {
  CLI::App* map = app.add_subcommand("map", "map clouds and write per-layer CSV files and pictures");
  add_mapping_options(map, o);
  add_output_options(map, o);
  CLI::Option* costmap = map->add_flag("--costmap", o.costmap,
                                       "also writes DIR/costmap_<k>.png and .pgm per layer: a planner's cost raster\n"
                                       "of layer k's cells (one pixel per cell of the picture's area, north up) in\n"
                                       "costmap_2d values as grey levels: 0 free .. 252 cost (inclination and\n"
                                       "relief against the layer's limits), 253 inscribed, 254 lethal (obstacle,\n"
                                       "steep or drop), 255 unknown or unobserved");
  add_value(map, "--inflate", "M", "with --costmap: cost pixels within M metres of a lethal one are inscribed",
            [&o](const std::string& v) {
              o.inflate = parse_number("--inflate", v);
              if (!(o.inflate >= 0.0) || !std::isfinite(o.inflate)) fail("--inflate: " + v + " is out of range (expected >= 0)", 2);
            })
      ->needs(costmap);
  add_name(map, "--save", "FILE", "a file name",
           "also writes a map for 'ccmap merge': the library's snapshot followed by the\n"
           "origin (tools/cli/saved_map.hpp). With --poses, the final map; without,\n"
           "the map of one stack at the origin holding the points that fall in its\n"
           "windows (what a rover there holds; the CSV files cover every tile)",
           &o.save);
  map->add_flag("--register", o.register_frames,
                "with --poses: registers every frame after the first against the map before\n"
                "it is folded in (the library's register_frame: the cells' planes, docs/design.md,\n"
                "'Registration'), prints the correction per frame ('registration N: ...'), and\n"
                "applies it to that frame and, as a rover corrects its pose, to the poses after it");
  map->footer(kMapFooter);
}

void add_query_command(CLI::App& app, Options& o) {
  CLI::App* query = app.add_subcommand("query", "map clouds and print the map's answer at one point or along a path");
  add_mapping_options(query, o);
  CLI::Option* at = add_value(query, "--at", "X,Y", "the map-frame point asked (absolute coordinates)",
                              [&o](const std::string& v) {
                                parse_pair("--at", v, &o.at_x, &o.at_y);
                                o.have_at = true;
                              });
  CLI::Option* footprint = add_value(
      query, "--footprint", "L,W[,YAW_DEG]",
      "with --at: also the rover body, an L x W m rectangle centred there, its\n"
      "length along YAW_DEG (degrees from +x, default 0): adds footprint_class\n"
      "(traversable|obstacle|steep|unknown), footprint_unknown_share, footprint_upset_share,\n"
      "footprint_max_step_m, footprint_max_inclination_deg",
      [&o](const std::string& v) {
        const std::vector<double> n = parse_list("--footprint", v, ',');
        if (n.size() < 2 || n.size() > 3) fail("--footprint: expected LENGTH,WIDTH[,YAW_DEG], got '" + v + "'", 2);
        for (std::size_t k = 0; k < n.size(); ++k) {
          if (!std::isfinite(n[k]) || (k < 2 && !(n[k] > 0.0))) {
            fail("--footprint: '" + v + "': length and width must be > 0, all finite", 2);
          }
        }
        o.footprint_length = n[0];
        o.footprint_width = n[1];
        o.footprint_has_yaw = n.size() == 3;
        o.footprint_yaw_deg = o.footprint_has_yaw ? n[2] : 0.0;
        o.have_footprint = true;
      });
  CLI::Option* path = add_value(query, "--path", "X1,Y1:X2,Y2[:...]",
                                "the body swept along this polyline (map frame, 2 .. 256 points),\n"
                                "its length along each segment: prints first_hazard_m (obstacle or steep)\n"
                                "and first_unknown_m, each a distance along the path or 'none'",
                                [&o](const std::string& v) { o.path = parse_path(v); });
  path->needs(footprint)->excludes(at);
  add_value(query, "--step", "M", "distance between the body's poses along --path (default: the finest cell)",
            [&o](const std::string& v) { o.step = parse_positive("--step", v, 100.0); })
      ->needs(path);
  add_value(query, "--max-unknown-share", "F", "a footprint with a larger unknown share is unknown (default 0.1)",
            [&o](const std::string& v) {
              o.max_unknown_share = parse_number("--max-unknown-share", v);
              if (!(o.max_unknown_share >= 0.0 && o.max_unknown_share <= 1.0)) {
                fail("--max-unknown-share: " + v + " is out of range (expected 0 .. 1)", 2);
              }
            });
  query->footer(kQueryFooter);
}

void add_merge_command(CLI::App& app, Options& o) {
  CLI::App* merge = app.add_subcommand("merge", "merge maps saved by 'ccmap map --save' (or snapshots) and write the same output");
  add_value(merge, "--preset", "NAME", "the maps' preset (cadre, ccm, kf or omg)", [&o](const std::string& v) { o.preset = v; })
      ->required();
  add_paper_cell_option(merge, o);
  add_repeated(merge, "--in", "FILE",
            "a saved map; give two or more. Merge only maps built independently: a map\n"
            "that already holds another's points counts them twice",
            [&o](const std::string& v) {
              if (v.empty()) fail("--in needs a file name", 2);
              o.inputs.push_back(v);
            });
  add_value(merge, "--offset", "DX,DY",
            "the map origin of every further --in relative to the first's (m): for\n"
            "snapshots without a saved origin; replaces the saved origins' difference.\n"
            "Must be a whole number of coarsest cells (cadre: 0.64 m), or the maps are\n"
            "refused as misaligned",
            [&o](const std::string& v) {
              parse_pair("--offset", v, &o.offset_x, &o.offset_y);
              o.have_offset = true;
            });
  merge->add_flag("--align", o.align,
                  "aligns each map with the first before merging it (the library's align_snapshot),\n"
                  "prints the correction ('alignment FILE: ...'), and merges with the nominal offset\n"
                  "plus the correction's observable part: dz exactly, the horizontal part rounded to\n"
                  "whole coarsest cells (the grids must coincide); the remainder and the yaw are\n"
                  "printed as not applied (docs/design.md, 'Merging at an offset that is not whole cells')");
  add_output_options(merge, o);
  merge->footer(kMergeFooter);
}

void add_product_command(CLI::App& app, Options& o) {
  CLI::App* product = app.add_subcommand("product", "check, print and draw a map product (what ccmap_publish writes)");
  add_name(product, "--in", "FILE", "a file name",
           "the product's bytes (from ccmap_product_read, Python's Map.product, a\n"
           "downlink); checked with the library's decoder (size, version, CRC)",
           &o.product_in)
      ->required();
  product->add_flag("--cells", o.product_cells, "also prints every cell: ix iy class cost status layer height_m inclination");
  add_name(product, "--png", "PREFIX", "a file name prefix",
           "also writes PREFIX_class.png, PREFIX_cost.png and PREFIX_height.png (north up)", &o.product_png);
}

/// For an option given to the wrong command: "--at belongs to 'ccmap query'", or empty when no
/// other command knows `arg` either.
std::string foreign_option_hint(const CLI::App& app, const CLI::App& used, const std::string& arg) {
  const std::string name = arg.substr(0, arg.find('='));
  if (name.rfind("--", 0) != 0) return {};
  std::vector<std::string> owners;
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; })) {
    if (sub != &used && sub->get_option_no_throw(name) != nullptr) owners.push_back("'ccmap " + sub->get_name() + "'");
  }
  if (owners.empty()) return {};
  std::string text = name + " belongs to " + owners[0];
  for (std::size_t i = 1; i < owners.size(); ++i) text += " and " + owners[i];
  if (used.get_name() == "merge") text += " (the maps bring their own parameters)";
  return text;
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
  std::string srs_wkt;                 ///< coordinate system of the GeoTIFFs: --epsg, else the first DEM's
};

const char* sensor_name(const Options& o) {
  return o.sensor == SensorChoice::kLidar ? "lidar" : "stereo (CADRE model)";
}

/// Frame f of the options: a cloud file, or a raster DEM read as a cloud (one point per cell
/// with data); the first DEM's coordinate system becomes the GeoTIFFs' when --epsg is not given.
Cloud read_frame(const Options& o, std::size_t f, MappedClouds& m) {
  const std::string& path = o.clouds[f];
  std::string srs;
  Cloud cloud = o.dem[f] ? read_dem(path, &srs) : read_cloud(path);
  if (!cloud.ok()) fail(cloud.error);
  if (m.srs_wkt.empty() && o.epsg == 0) m.srs_wkt = srs;
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
         std::to_string(s.too_noisy) +
         (s.gated > 0 ? ", outlier gate " + std::to_string(s.gated) + " (admitted later " +
                            std::to_string(s.gated_admitted) + ")"
                      : std::string());
}

void print_frame(const std::string& path, const Cloud& cloud, std::size_t f, const FrameStats& stats, double ms,
                 std::ostream& out) {
  out << "frame " << (f + 1) << ": " << base_name(path) << " [" << cloud.format << "]: " << cloud.declared
      << " points, " << counts_text(stats) << "; " << fmt("%.1f", ms) << " ms\n";
  if (cloud.has_weight) {
    out << "note: " << base_name(path) << ": per-point weights from the file replace the sensor model's\n";
  }
}

/// The cloud's points in range and bounds as local-frame floats (the origin subtracted in double,
/// then rounded: |difference| <= 1e5 m) and their weights; the others counted in *kept_back as
/// out of range or outside map.
void local_frame_points(const Cloud& cloud, const LocalOrigin& origin, const AreaBounds& bounds,
                        std::vector<float>* xyz, std::vector<float>* weights, FrameStats* kept_back) {
  xyz->clear();
  weights->clear();
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const PointFate fate = classify_point(cloud.x[i], cloud.y[i], cloud.z[i], origin, bounds);
    if (fate == PointFate::kOutOfRange) {
      ++kept_back->rejected_out_of_range;
      continue;
    }
    if (fate == PointFate::kOutsideBounds) {
      ++kept_back->outside_map;
      continue;
    }
    xyz->push_back(static_cast<float>(cloud.x[i] - origin.xyz[0]));
    xyz->push_back(static_cast<float>(cloud.y[i] - origin.xyz[1]));
    xyz->push_back(static_cast<float>(cloud.z[i] - origin.xyz[2]));
    if (cloud.has_weight) weights->push_back(weight_to_float(cloud.w[i]));
  }
}

/// Folds cloud number f as one frame, the sensor at `sensor` (local metres): the points the tool
/// maps (local_frame_points), the others counted.
void fold_cloud(const Options& o, MappedClouds& m, const Cloud& cloud, std::size_t f, const float sensor[3],
                std::vector<float>* xyz, std::vector<float>* weights, std::ostream& out, bool verbose) {
  std::string error;
  FrameStats stats;
  stats.received = cloud.size() + cloud.skipped_non_finite;
  stats.rejected_non_finite = cloud.skipped_non_finite;
  local_frame_points(cloud, m.origin, o.bounds, xyz, weights, &stats);
  FrameStats lib;
  const auto t0 = std::chrono::steady_clock::now();
  if (!m.runner->update_frame(*xyz, *weights, sensor, &lib, &error)) fail(o.clouds[f] + ": " + error);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  lib.received = 0;  // counted above, with the points the tool kept back
  stats.add(lib);
  m.totals.add(stats);
  if (verbose) print_frame(o.clouds[f], cloud, f, stats, ms, out);
}

/// "observable: dx dy dz dyaw" flags as 0/1.
std::string correction_text(const LocalCorrection& c) {
  std::string t = c.status + " correction " + fmt("%.4f", c.correction[0]) + ' ' + fmt("%.4f", c.correction[1]) + ' ' +
                  fmt("%.4f", c.correction[2]) + " m " + fmt("%.5f", c.correction[3]) + " rad, sigma";
  for (int k = 0; k < 4; ++k) t += ' ' + (std::isfinite(c.sigma[k]) ? fmt(k == 3 ? "%.5f" : "%.4f", c.sigma[k]) : std::string("inf"));
  t += ", observable";
  for (int k = 0; k < 4; ++k) t += c.observable[k] ? " 1" : " 0";
  return t + ", " + std::to_string(c.iterations) + " iterations";
}

/// map --register: frame f (f > 0) moved by the corrections so far, registered against the map,
/// its correction printed and composed into them, then the frame (moved by the new total) folded
/// in. The first frame starts the map and is folded as it is.
void register_and_fold(const Options& o, MappedClouds& m, const Cloud& cloud, std::size_t f, const Pose& p,
                       double* cos_yaw, double* sin_yaw, double* tx, double* ty, double* tz, std::vector<float>* xyz,
                       std::vector<float>* weights, std::ostream& out, bool verbose) {
  std::string error;
  const double pose_local[3] = {p.x - m.origin.xyz[0], p.y - m.origin.xyz[1], p.z - m.origin.xyz[2]};
  for (double v : pose_local) {
    if (!(std::fabs(v) <= static_cast<double>(kMaxAbsCoordinateM))) {
      fail(o.poses + ": pose " + std::to_string(f + 1) + " lies beyond +-1e5 m of the origin; is it in the clouds' frame?");
    }
  }
  FrameStats stats;
  stats.received = cloud.size() + cloud.skipped_non_finite;
  stats.rejected_non_finite = cloud.skipped_non_finite;
  local_frame_points(cloud, m.origin, o.bounds, xyz, weights, &stats);
  // Moves the frame's points and the sensor by the corrections so far.
  auto apply = [&](double c, double s, double ax, double ay, double az, const double in[3], double* outp) {
    outp[0] = c * in[0] - s * in[1] + ax;
    outp[1] = s * in[0] + c * in[1] + ay;
    outp[2] = in[2] + az;
  };
  std::vector<float> moved(xyz->size());
  double sensor_d[3];
  apply(*cos_yaw, *sin_yaw, *tx, *ty, *tz, pose_local, sensor_d);
  for (std::size_t i = 0; i + 2 < xyz->size(); i += 3) {
    const double in[3] = {(*xyz)[i], (*xyz)[i + 1], (*xyz)[i + 2]};
    double q[3];
    apply(*cos_yaw, *sin_yaw, *tx, *ty, *tz, in, q);
    for (int a = 0; a < 3; ++a) moved[i + static_cast<std::size_t>(a)] = static_cast<float>(q[a]);
  }
  float sensor[3] = {static_cast<float>(sensor_d[0]), static_cast<float>(sensor_d[1]), static_cast<float>(sensor_d[2])};
  if (!m.runner->move_to(sensor[0], sensor[1], &error)) {
    fail(o.poses + ": pose " + std::to_string(f + 1) + ": " + error + "; is it in the clouds' frame?");
  }
  if (f > 0) {
    const LocalCorrection c = m.runner->register_frame(moved, sensor);
    out << "registration " << (f + 1) << ": " << base_name(o.clouds[f]) << ": " << correction_text(c) << "\n";
    if (c.status == "ok") {
      // The new correction about the sensor o: q = Rz(a)(p - o) + o + d, composed after the old.
      const double ca = std::cos(c.correction[3]), sa = std::sin(c.correction[3]);
      const double ox = sensor_d[0], oy = sensor_d[1];
      const double nx = ca * (*tx - ox) - sa * (*ty - oy) + ox + c.correction[0];
      const double ny = sa * (*tx - ox) + ca * (*ty - oy) + oy + c.correction[1];
      const double nc = ca * *cos_yaw - sa * *sin_yaw, ns = sa * *cos_yaw + ca * *sin_yaw;
      *tx = nx;
      *ty = ny;
      *tz += c.correction[2];
      *cos_yaw = nc;
      *sin_yaw = ns;
      for (std::size_t i = 0; i + 2 < xyz->size(); i += 3) {
        const double in[3] = {(*xyz)[i], (*xyz)[i + 1], (*xyz)[i + 2]};
        double q[3];
        apply(*cos_yaw, *sin_yaw, *tx, *ty, *tz, in, q);
        for (int a = 0; a < 3; ++a) moved[i + static_cast<std::size_t>(a)] = static_cast<float>(q[a]);
      }
      apply(*cos_yaw, *sin_yaw, *tx, *ty, *tz, pose_local, sensor_d);
      for (int a = 0; a < 3; ++a) sensor[a] = static_cast<float>(sensor_d[a]);
      if (!m.runner->move_to(sensor[0], sensor[1], &error)) fail(o.clouds[f] + ": " + error);
    }
  }
  FrameStats lib;
  const auto t0 = std::chrono::steady_clock::now();
  if (!m.runner->update_frame(moved, *weights, sensor, &lib, &error)) fail(o.clouds[f] + ": " + error);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  lib.received = 0;
  stats.add(lib);
  m.totals.add(stats);
  if (verbose) print_frame(o.clouds[f], cloud, f, stats, ms, out);
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
  // --register: the correction so far, p' = R p + t in the local frame (R about z), applied to
  // every frame before it is registered, as a rover's pose estimate carries the corrections.
  double cos_yaw = 1.0, sin_yaw = 0.0, tx = 0.0, ty = 0.0, tz = 0.0;
  for (std::size_t f = 0; f < o.clouds.size(); ++f) {
    const Cloud cloud = read_frame(o, f, m);
    m.read += cloud.declared;
    if (f == 0) {
      if (!robust_origin({&cloud}, o.bounds, m.widths.back(), &m.origin, &error)) fail(o.clouds[f] + ": " + error);
      if (verbose) print_header(o, m, out);
    }
    if (o.register_frames) {
      register_and_fold(o, m, cloud, f, poses[f], &cos_yaw, &sin_yaw, &tx, &ty, &tz, &xyz, &weights, out, verbose);
      continue;
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
    fold_cloud(o, m, cloud, f, sensor, &xyz, &weights, out, verbose);
  }
}

/// Every cloud read at once (tiles and the centred map need them all), the local origin from
/// all of them, the header printed.
std::vector<Cloud> read_all_clouds(const Options& o, MappedClouds& m, std::ostream& out, bool verbose) {
  std::string error;
  std::vector<Cloud> clouds;
  std::vector<const Cloud*> all;
  clouds.reserve(o.clouds.size());
  for (std::size_t f = 0; f < o.clouds.size(); ++f) {
    clouds.push_back(read_frame(o, f, m));
    m.read += clouds.back().declared;
  }
  for (const Cloud& c : clouds) all.push_back(&c);
  if (!robust_origin(all, o.bounds, m.widths.back(), &m.origin, &error)) fail(error);
  if (verbose) print_header(o, m, out);
  return clouds;
}

/// A planner query without --poses: the stack centred on (x, y) (map frame), every cloud folded
/// into it as one frame with the sensor there (at the origin's height), as a rover standing at
/// (x, y) would map the ground. The origin is that of all clouds, as for tiles.
void map_centred(const Options& o, MappedClouds& m, double x, double y, std::ostream& out, bool verbose) {
  std::string error;
  const std::vector<Cloud> clouds = read_all_clouds(o, m, out, verbose);
  const double local[2] = {x - m.origin.xyz[0], y - m.origin.xyz[1]};
  if (!(std::fabs(local[0]) <= static_cast<double>(kMaxAbsCoordinateM)) ||
      !(std::fabs(local[1]) <= static_cast<double>(kMaxAbsCoordinateM))) {
    fail("the query lies beyond +-1e5 m of the clouds' origin", 2);
  }
  const float sensor[3] = {static_cast<float>(local[0]), static_cast<float>(local[1]), 0.0F};
  if (!m.runner->move_to(sensor[0], sensor[1], &error)) fail(error);
  if (verbose) {
    out << "map centred on the query (" << fmt("%.3f", x) << ", " << fmt("%.3f", y) << "), every cloud one frame\n";
  }
  std::vector<float> xyz, weights;
  for (std::size_t f = 0; f < clouds.size(); ++f) fold_cloud(o, m, clouds[f], f, sensor, &xyz, &weights, out, verbose);
}

/// Without --poses: the stack is swept over all clouds in tiles (tiling.hpp), so every layer
/// covers their whole extent. For a query only the query point's tile is mapped.
void map_in_tiles(const Options& o, MappedClouds& m, std::ostream& out, bool verbose) {
  std::string error;
  const std::vector<Cloud> clouds = read_all_clouds(o, m, out, verbose);
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
  std::string error;
  MappedClouds m;
  m.runner = make_map_runner(o.preset, o.paper_cell, &error);
  if (!m.runner) fail(error, 2);
  if (o.clouds.empty()) fail("at least one --cloud FILE (or --dem FILE) is required", 2);

  const int layers = preset_layer_count(o.preset);
  const double finest = o.res > 0.0 ? o.res : preset_default_cell_width(o.preset);
  for (int k = 0; k < layers; ++k) m.widths.push_back(finest * std::ldexp(1.0, k));

  RunnerOptions ro;
  ro.preset = o.preset;
  ro.finest_cell_width_m = finest;
  ro.weight_limit = o.wl;
  ro.outlier_gate_sigma = o.gate;
  ro.sensor = o.sensor;
  ro.lidar_sigma_m = o.sigma;
  if (!m.runner->init(ro, &error)) fail(error);

  if (o.centred_map()) {
    const bool path = !o.path.empty();
    map_centred(o, m, path ? o.path[0] : o.at_x, path ? o.path[1] : o.at_y, out, verbose);
  } else if (o.poses.empty()) {
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

/// Writes a cost raster (width x height, row 0 at the lowest y) as a binary PGM and a grey PNG,
/// north up.
void write_costmap_images(const std::string& prefix, const std::vector<std::uint8_t>& cost, int width, int height) {
  std::string error;
  RgbImage image(width, height);
  std::vector<unsigned char> rows;
  rows.reserve(cost.size());
  for (int row = 0; row < height; ++row) {
    const int iy = height - 1 - row;  // north up
    for (int ix = 0; ix < width; ++ix) {
      const std::uint8_t v = cost[static_cast<std::size_t>(iy) * static_cast<std::size_t>(width) + static_cast<std::size_t>(ix)];
      const std::uint8_t grey[3] = {v, v, v};
      image.set(ix, row, grey);
      rows.push_back(v);
    }
  }
  if (!write_png(prefix + ".png", image, &error)) fail(error);
  std::ofstream pgm(prefix + ".pgm", std::ios::binary);
  pgm << "P5\n" << width << ' ' << height << "\n255\n";
  pgm.write(reinterpret_cast<const char*>(rows.data()), static_cast<std::streamsize>(rows.size()));
  if (!pgm) fail("cannot write " + prefix + ".pgm");
}

/// The cost raster of layer k's cells over `extent` (one pixel per cell): lethal for obstacle,
/// steep and drop-off cells, unknown for unknown or unobserved ones, else the library's cost function of
/// the cell's inclination and normal variance against layer k's threshold; then the inflation.
std::vector<std::uint8_t> layer_costmap(const MappedClouds& m, int k, const std::vector<LayerCellRow>& rows,
                                        const LayerWindow& extent, double inflate_m) {
  std::vector<std::uint8_t> cost(static_cast<std::size_t>(extent.nx) * static_cast<std::size_t>(extent.ny), kCostUnknown);
  const float threshold = m.runner->layer_normal_variance_threshold(k);
  const float max_inclination = m.runner->max_inclination();
  for (const LayerCellRow& r : rows) {
    const std::int64_t ix = r.ix - extent.ix_min, iy = r.iy - extent.iy_min;
    if (ix < 0 || iy < 0 || ix >= extent.nx || iy >= extent.ny) continue;
    std::uint8_t v = kCostUnknown;
    if (r.cell_class == "obstacle" || r.cell_class == "steep" || r.cell_class == "drop") {
      v = kCostLethal;
    } else if (r.cell_class == "traversable") {
      v = traversable_cost(static_cast<float>(std::hypot(r.slope_x, r.slope_y)), max_inclination,
                           static_cast<float>(r.normal_var), threshold);
    }
    cost[static_cast<std::size_t>(iy) * static_cast<std::size_t>(extent.nx) + static_cast<std::size_t>(ix)] = v;
  }
  if (inflate_m > 0.0) {
    const Status status = inflate_costmap(cost.data(), cost.size(), static_cast<std::uint32_t>(extent.nx),
                                          static_cast<std::uint32_t>(extent.ny),
                                          static_cast<float>(inflate_m / m.widths[static_cast<std::size_t>(k)]));
    if (status != Status::kOk) {
      fail("--inflate: " + fmt("%g", inflate_m) + " m is " + fmt("%g", inflate_m / m.widths[static_cast<std::size_t>(k)]) +
               " cells of layer " + std::to_string(k) + " (" + to_string(status) + ": at most " +
               std::to_string(kMaxInflationPixels) + ")",
           2);
    }
  }
  return cost;
}

/// The CSV files and pictures of every layer, in absolute coordinates, and a line per layer: the
/// tiles' rows of a tiled map, else the runner's current state.
void write_outputs(MappedClouds& m, const Options& o, std::ostream& out) {
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
    } else {
      if (!write_layer_images(prefix, rows, window, &error)) fail(error);
      if (o.geotiff && !write_layer_geotiff(prefix + ".tif", rows, extent, m.widths[static_cast<std::size_t>(k)],
                                            m.srs_wkt, &error)) {
        fail(error);
      }
      if (o.costmap) {
        const std::vector<std::uint8_t> cost = layer_costmap(m, k, rows, extent, o.inflate);
        const std::string cost_prefix = o.out_dir + "/costmap_" + std::to_string(k);
        write_costmap_images(cost_prefix, cost, static_cast<int>(extent.nx), static_cast<int>(extent.ny));
        std::size_t counts[4] = {0, 0, 0, 0};  // free/cost, inscribed, lethal, unknown
        for (const std::uint8_t v : cost) ++counts[v <= kCostMaxTraversable ? 0 : v - kCostMaxTraversable];
        out << "costmap " << k << " (" << extent.nx << " x " << extent.ny << " at "
            << fmt("%g", m.widths[static_cast<std::size_t>(k)]) << " m): cost " << counts[0] << ", inscribed "
            << counts[1] << ", lethal " << counts[2] << ", unknown " << counts[3] << " pixels -> " << cost_prefix
            << ".{png,pgm}\n";
      }
    }
    std::size_t counts[5] = {0, 0, 0, 0, 0};
    for (const LayerCellRow& r : rows) {
      if (r.cell_class == "traversable") ++counts[1];
      else if (r.cell_class == "obstacle") ++counts[2];
      else if (r.cell_class == "steep") ++counts[3];
      else if (r.cell_class == "drop") ++counts[4];
      else ++counts[0];
    }
    out << "layer " << k << " (" << fmt("%g", m.widths[static_cast<std::size_t>(k)]) << " m, "
        << (m.tiled ? "tiled" : std::to_string(side) + " x " + std::to_string(side)) << ", "
        << (m.runner->layer_is_ccm(k) ? "CCM" : (o.preset == "omg" ? "OMG" : "Kalman"))
        << "): " << (rows.size() - counts[0]) << " cells known of " << rows.size() << " observed (traversable "
        << counts[1] << ", obstacle " << counts[2] << ", steep " << counts[3] << ", unknown " << counts[0]
        << (counts[4] > 0 ? ", drop " + std::to_string(counts[4]) : std::string()) << ") -> " << prefix << ".csv\n";
  }
  out << "pictures: " << o.out_dir << "/layer_<k>_{height,slope,normal_var,class}.png, north up, observed area"
      << " (class: unknown grey, traversable green, obstacle red, steep orange, drop purple; unobserved black)\n";
  if (o.geotiff) {
    out << "geotiff: " << o.out_dir << "/layer_<k>.tif, the pictures' area in absolute coordinates ("
        << (o.epsg > 0 ? "EPSG:" + std::to_string(o.epsg) : (m.srs_wkt.empty() ? "no coordinate system" : "the DEM's coordinate system"))
        << "); bands height, slope_x, slope_y, normal_var, class (0 unknown, 1 traversable, 2 obstacle, 3 steep, 4 drop), NaN unobserved\n";
  }
}

/// --geotiff, --epsg and --dem: refused up front (exit 2) in a build without GDAL or with an
/// unknown EPSG code, before any cloud is read. Returns the GeoTIFFs' coordinate system of --epsg
/// (empty without it).
std::string check_raster_options(const Options& o) {
  const bool any_dem = std::find(o.dem.begin(), o.dem.end(), true) != o.dem.end();
  if ((o.geotiff || any_dem) && !raster_io_available()) {
    fail(std::string(o.geotiff ? "--geotiff" : "--dem") + ": " + raster_io_unavailable_reason(), 2);
  }
  std::string wkt, error;
  if (o.epsg > 0 && !srs_from_epsg(o.epsg, &wkt, &error)) fail("--epsg: " + error, 2);
  return wkt;
}

/// A tiled map has no single stack: the saved map is that of one stack at the origin, every cloud
/// one frame (sensor at the origin, as in the tiles), holding the points its windows hold.
void fold_one_window(const Options& o, MappedClouds& m, std::ostream& out) {
  std::string error;
  if (!m.runner->reset(&error) || !m.runner->move_to(0.0F, 0.0F, &error)) fail(error);
  const float sensor[3] = {0.0F, 0.0F, 0.0F};
  FrameStats totals;
  std::vector<float> xyz, weights;
  for (std::size_t f = 0; f < o.clouds.size(); ++f) {
    const std::string& path = o.clouds[f];
    const Cloud cloud = read_frame(o, f, m);
    FrameStats kept_back;
    local_frame_points(cloud, m.origin, o.bounds, &xyz, &weights, &kept_back);
    FrameStats stats;
    if (!m.runner->update_frame(xyz, weights, sensor, &stats, &error)) fail(path + ": " + error);
    totals.add(stats);
    totals.add(kept_back);
  }
  out << "saved map: one stack at the origin, " << totals.used << " points in its windows, " << totals.outside_map
      << " outside them\n";
}

int run_map(const Options& o, std::ostream& out) {
  if (o.register_frames && o.poses.empty()) {
    fail("--register needs --poses: the frames of a rover, in order (without, the clouds are tiles of one map)", 2);
  }
  const std::string epsg_wkt = check_raster_options(o);
  MappedClouds m = build_map(o, out, true);
  if (o.epsg > 0) m.srs_wkt = epsg_wkt;
  write_outputs(m, o, out);
  if (!o.save.empty()) {
    if (m.tiled) fold_one_window(o, m, out);
    std::string error;
    SavedMap saved;
    if (!m.runner->save_snapshot(&saved.snapshot, &error)) fail(error);
    saved.has_origin = true;
    saved.coarsest_width_m = m.origin.coarsest_width;
    for (int a = 0; a < 3; ++a) saved.origin_cells[a] = m.origin.cells[a];
    if (!write_saved_map(o.save, saved, &error)) fail(error);
    out << "saved: " << o.save << " (" << saved.snapshot.size() + kOriginRecordBytes
        << " bytes: snapshot and origin)\n";
  }
  return 0;
}

/// metres / width as an exact integer, or fail: the maps do not share the grid.
std::int64_t whole_cells(double metres, double width, const std::string& what) {
  const double cells = metres / width;
  const double rounded = std::round(cells);
  if (!(std::fabs(cells - rounded) <= 1e-6 * std::max(1.0, std::fabs(rounded))) || std::fabs(rounded) > 1e15) {
    fail(what + ": " + fmt("%.6f", metres) + " m is not a whole number of " + fmt("%g", width) +
         " m cells (misaligned)");
  }
  return static_cast<std::int64_t>(rounded);
}

int run_merge(const Options& o, std::ostream& out) {
  if (o.inputs.size() < 2) fail("ccmap merge needs two or more --in FILE", 2);
  std::string error;
  MappedClouds m;
  m.srs_wkt = check_raster_options(o);
  m.runner = make_map_runner(o.preset, o.paper_cell, &error);
  if (!m.runner) fail(error, 2);
  const int layers = preset_layer_count(o.preset);
  const std::int64_t coarse_factor = std::int64_t{1} << (layers - 1);  // finest cells per coarsest cell
  std::vector<SavedMap> maps(o.inputs.size());
  for (std::size_t i = 0; i < o.inputs.size(); ++i) {
    if (!read_saved_map(o.inputs[i], m.runner->snapshot_size(), &maps[i], &error)) {
      // A map of the other CCM cell kind has another size: say which flag would read it.
      const std::string kind = !preset_has_ccm(o.preset) ? ""
                               : o.paper_cell             ? " of paper cells (saved with --paper-cell)"
                                                          : " of full cells (saved without --paper-cell)";
      fail(error + " (is it a " + o.preset + " map" + kind + "?)");
    }
  }
  if (!m.runner->load_snapshot(maps[0].snapshot, &error)) fail(o.inputs[0] + ": " + error);
  // Widths: the saved origin's double width (what 'ccmap map' computed with), else the float
  // width rounded to the decimal a user would type.
  const SavedMap& first = maps[0];
  const double coarsest = first.has_origin
                              ? first.coarsest_width_m
                              : std::round(static_cast<double>(m.runner->layer_cell_width(layers - 1)) * 1e6) / 1e6;
  for (int k = 0; k < layers; ++k) m.widths.push_back(coarsest * std::ldexp(1.0, k - (layers - 1)));
  m.origin.coarsest_width = coarsest;
  for (int a = 0; a < 3; ++a) {
    m.origin.cells[a] = first.origin_cells[a];
    m.origin.xyz[a] = static_cast<double>(first.origin_cells[a]) * coarsest;
  }
  out << "ccmap merge: preset " << o.preset << ", " << o.inputs[0] << " (origin " << fmt("%.3f", m.origin.xyz[0])
      << ' ' << fmt("%.3f", m.origin.xyz[1]) << ' ' << fmt("%.3f", m.origin.xyz[2])
      << (first.has_origin ? "" : ", none saved") << ") holds the parameters and windows\n";
  for (std::size_t i = 1; i < maps.size(); ++i) {
    const SavedMap& other = maps[i];
    if (other.has_origin && std::fabs(other.coarsest_width_m - coarsest) > 1e-12 * coarsest) {
      fail(o.inputs[i] + ": made with " + fmt("%g", other.coarsest_width_m) + " m coarsest cells, the first with " +
           fmt("%g", coarsest) + " m (misaligned)");
    }
    // The other map's origin minus the first's: in coarsest cells (x, y), metres (z).
    std::int64_t dx = other.origin_cells[0] - first.origin_cells[0];
    std::int64_t dy = other.origin_cells[1] - first.origin_cells[1];
    if (o.have_offset) {
      dx = whole_cells(o.offset_x, coarsest, "--offset x");
      dy = whole_cells(o.offset_y, coarsest, "--offset y");
    }
    double dz = static_cast<double>(other.origin_cells[2] - first.origin_cells[2]) * coarsest;
    if (o.align) {
      // The correction of the other map placed by the nominal offset, about its cells' centre c:
      // q = Rz(a)(p - c) + c + d. What the grid can take exactly: dz (heights move), and the
      // horizontal displacement at c, d, to the nearest whole coarsest cell. The rest of d and
      // the yaw (a cell at distance r from c moves r * a) are not applied.
      const double nominal[3] = {static_cast<double>(dx) * coarsest, static_cast<double>(dy) * coarsest, dz};
      const LocalCorrection c = m.runner->align_snapshot(other.snapshot, nominal);
      out << "alignment " << o.inputs[i] << ": " << correction_text(c) << ", centre " << fmt("%.3f", c.centre[0]) << ' '
          << fmt("%.3f", c.centre[1]) << " m (local), " << c.cells << " cells\n";
      if (c.status == "ok") {
        const double ax = c.observable[0] ? c.correction[0] : 0.0;
        const double ay = c.observable[1] ? c.correction[1] : 0.0;
        const auto rx = static_cast<std::int64_t>(std::llround(ax / coarsest));
        const auto ry = static_cast<std::int64_t>(std::llround(ay / coarsest));
        dx += rx;
        dy += ry;
        if (c.observable[2]) dz += c.correction[2];
        out << "alignment " << o.inputs[i] << ": applied " << fmt("%.3f", static_cast<double>(rx) * coarsest) << ' '
            << fmt("%.3f", static_cast<double>(ry) * coarsest) << ' ' << fmt("%.4f", c.observable[2] ? c.correction[2] : 0.0)
            << " m; not applied " << fmt("%.4f", ax - static_cast<double>(rx) * coarsest) << ' '
            << fmt("%.4f", ay - static_cast<double>(ry) * coarsest) << " m and " << fmt("%.5f", c.correction[3])
            << " rad (whole " << fmt("%g", coarsest) << " m cells only)\n";
      }
    }
    const std::int64_t fx = dx * coarse_factor, fy = dy * coarse_factor;
    if (std::llabs(fx) > 0x3FFFFFFF || std::llabs(fy) > 0x3FFFFFFF || std::fabs(dz) > 1e5) {
      fail(o.inputs[i] + ": its origin is too far from the first map's to merge");
    }
    std::uint64_t merged = 0, outside = 0;
    if (!m.runner->merge_snapshot(other.snapshot, static_cast<std::int32_t>(fx), static_cast<std::int32_t>(fy),
                                  static_cast<float>(dz), &merged, &outside, &error)) {
      fail(o.inputs[i] + ": " + error);
    }
    out << "merged " << o.inputs[i] << ": offset " << fmt("%.3f", static_cast<double>(dx) * coarsest) << ' '
        << fmt("%.3f", static_cast<double>(dy) * coarsest) << ' ' << fmt("%.3f", dz) << " m, " << merged
        << " cells merged, " << outside << " outside the first map's windows (dropped)\n";
  }
  write_outputs(m, o, out);
  return 0;
}

/// The path query: first_hazard_m / first_unknown_m lines.
int run_path_query(const Options& o, const MappedClouds& m, std::ostream& out) {
  if (!o.have_footprint) fail("--path needs --footprint LENGTH,WIDTH (the body swept along it)", 2);
  if (o.footprint_has_yaw) fail("--footprint: YAW_DEG does not apply to --path (the body follows the path)", 2);
  std::vector<float> xy;
  for (std::size_t i = 0; i < o.path.size(); i += 2) {
    xy.push_back(static_cast<float>(o.path[i] - m.origin.xyz[0]));
    xy.push_back(static_cast<float>(o.path[i + 1] - m.origin.xyz[1]));
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
    out << "hazard_x: " << fmt("%.6f", static_cast<double>(p.hazard_x) + m.origin.xyz[0]) << "\n";
    out << "hazard_y: " << fmt("%.6f", static_cast<double>(p.hazard_y) + m.origin.xyz[1]) << "\n";
  }
  out << "first_unknown_m: " << (p.unknown ? fmt("%.6f", p.first_unknown_m) : std::string("none")) << "\n";
  return 0;
}

int run_query(const Options& o, std::ostream& out) {
  if (!o.have_at && o.path.empty()) fail("--at X,Y or --path X1,Y1:X2,Y2[:...] is required", 2);
  check_raster_options(o);
  std::ostringstream log;
  MappedClouds m = build_map(o, log, true);
  if (!o.path.empty()) return run_path_query(o, m, out);
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
  out << "upset: " << (q.upset ? 1 : 0) << "\n";
  if (o.have_footprint) {
    // The centred map (map_centred) or the map at the last pose: never tiles.
    const double lx = o.at_x - m.origin.xyz[0], ly = o.at_y - m.origin.xyz[1];
    const double yaw = o.footprint_yaw_deg * kPi / 180.0;
    const LocalFootprint f = m.runner->footprint(
        static_cast<float>(lx), static_cast<float>(ly), static_cast<float>(std::cos(yaw)), static_cast<float>(std::sin(yaw)),
        static_cast<float>(o.footprint_length), static_cast<float>(o.footprint_width), static_cast<float>(o.max_unknown_share));
    if (f.status != "ok" && f.status != "outside_map") fail("the map refused the footprint (" + f.status + ")", 2);
    out << "footprint_class: " << f.verdict << "\n";
    out << "footprint_unknown_share: " << fmt("%.6f", f.unknown_share) << "\n";
    out << "footprint_upset_share: " << fmt("%.6f", f.upset_share) << "\n";
    out << "footprint_max_step_m: " << fmt("%.6f", f.max_step) << "\n";
    out << "footprint_max_inclination_deg: "
        << fmt("%.3f", std::atan(static_cast<double>(f.max_inclination)) * 180.0 / kPi) << "\n";
  }
  return 0;
}

}  // namespace

int run_cli(int argc, char** argv, std::ostream& out, std::ostream& err) {
  try {
    Options o;
    CLI::App app("Builds Converging Covariance Maps (CCM) from point clouds.", "ccmap");
    app.get_formatter()->label("Usage", "usage");
    app.get_formatter()->column_width(34);
    app.require_subcommand(1);
    app.footer("Run 'ccmap map --help', 'ccmap query --help', 'ccmap merge --help' or 'ccmap product --help' for\nthe options.");
    add_map_command(app, o);
    add_query_command(app, o);
    add_merge_command(app, o);
    add_product_command(app, o);
    if (argc >= 2 && argv != nullptr && argv[1] != nullptr && argv[1][0] != '-') {
      const std::string command = argv[1];
      if (command == "help") {
        out << app.help();
        return 0;
      }
      if (command != "map" && command != "query" && command != "merge" && command != "product") {
        fail("unknown command '" + command + "' (expected map, query, merge or product)", 2);
      }
    }
    try {
      app.parse(argc, argv);
    } catch (const CLI::CallForHelp&) {
      out << app.help();  // the selected command's, else the overview
      return 0;
    } catch (const CLI::ExtrasError& e) {
      const std::vector<CLI::App*> used = app.get_subcommands();
      std::string hint;
      for (const std::string& extra : app.remaining(true)) {
        if (hint.empty() && !used.empty()) hint = foreign_option_hint(app, *used[0], extra);
      }
      fail(hint.empty() ? e.what() : hint, 2);
    } catch (const CLI::ParseError& e) {
      std::string message = e.what();
      std::replace(message.begin(), message.end(), '\n', ' ');
      fail(message, 2);
    }
    o.command = app.get_subcommands().at(0)->get_name();
    if (o.command == "merge") return run_merge(o, out);
    if (o.command == "product") {
      std::string error;
      const int code = view_product(o.product_in, o.product_cells, o.product_png, out, &error);
      if (code != 0) fail(error, code);
      return 0;
    }
    return o.command == "map" ? run_map(o, out) : run_query(o, out);
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
