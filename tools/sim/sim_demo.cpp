// ccmap_sim_demo: one stereo frame over a lunar-like terrain. Prints the ray-casting time of a
// full 850 x 650 frame and writes the depth image and a top view of the points as PNGs.
//   ccmap_sim_demo [--seed N] [--out DIR] [--stride K] [--res M] [--pitch DEG] [--streaks P]
// (ccmap_sim_demo --help lists them; bad values are refused with one line and exit 2).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <cstring>
#include <filesystem>
#include <string>

#include "number_options.hpp"
#include "parse_args.hpp"
#include "png.hpp"
#include "sim/rng.hpp"
#include "sim/stereo.hpp"
#include "sim/terrain.hpp"

int main(int argc, char** argv) {
  std::uint64_t seed = 1;
  std::string out = "out/sim";
  int stride = 1;
  double res = 0.01, pitch = 25.0, streaks = 0.0;
  CLI::App app("One simulated CADRE stereo frame over lunar-like terrain: ray-casting time, depth image and\n"
               "top view (PNG).", "ccmap_sim_demo");
  // Numbers through tools/args/number_options.hpp: base 10, finite (CLI::Range lets NaN through
  // and CLI11 reads integers in base 0).
  ccmap::tools::add_whole<std::uint64_t>(app, "--seed", &seed, 0, UINT64_MAX, "N", "terrain and noise seed");
  app.add_option("--out", out, "output directory (sim_depth.png, sim_topview.png)")->capture_default_str();
  ccmap::tools::add_whole<int>(app, "--stride", &stride, 1, 650, "K", "cast every K-th pixel of the 850 x 650 frame");
  ccmap::tools::add_real(app, "--res", &res, 0.001, 1.0, false, "M", "terrain raster cell (m)");
  ccmap::tools::add_real(app, "--pitch", &pitch, 0.0, 89.0, false, "DEG", "camera pitch below the horizon (degrees)");
  ccmap::tools::add_real(app, "--streaks", &streaks, 0.0, 1.0, false, "P", "probability of a streak at a depth border");
  if (const int code = ccmap::tools::parse_args(app, argc, argv); code >= 0) return code;
  using ccmap::sim::Rect;
  const Rect area{0.0, 0.0, 20.0, 20.0};
  const auto t0 = std::chrono::steady_clock::now();
  const ccmap::sim::ProceduralTerrain terrain(ccmap::sim::lunar_terrain_params(area, seed));
  const ccmap::sim::HeightRaster raster = ccmap::sim::rasterize(terrain, area, res);
  const auto t1 = std::chrono::steady_clock::now();
  ccmap::sim::StereoParams sp;
  sp.pixel_stride = stride;
  sp.pitch_deg = pitch;
  sp.border_streak_probability = streaks;
  const ccmap::sim::StereoCamera camera(sp);
  const ccmap::sim::Pose2 pose{2.0, 4.0, 0.5};
  // CPU time (one core), not wall time: the figure should not depend on other load.
  const std::clock_t t2 = std::clock();
  const ccmap::sim::StereoFrame frame = camera.capture(raster, pose, seed);
  const std::clock_t t3 = std::clock();
  const ccmap::sim::DepthImage depth = camera.render_depth(raster, pose);
  const std::clock_t t4 = std::clock();
  auto cpu_ms = [](std::clock_t a, std::clock_t b) { return 1000.0 * static_cast<double>(b - a) / CLOCKS_PER_SEC; };
  auto ms = [](auto a, auto b) { return std::chrono::duration<double, std::milli>(b - a).count(); };
  std::printf("terrain: %zu rocks, %zu craters; raster %d x %d at %.3f m built in %.0f ms\n", terrain.rocks().size(),
              terrain.craters().size(), raster.nx(), raster.ny(), res, ms(t0, t1));
  std::printf("frame %d x %d (stride %d): %zu rays, %zu hits, %zu points, %zu streak pixels\n", sp.width_px,
              sp.height_px, stride, frame.rays_cast, frame.rays_hit, frame.points_map.size(), frame.streak_pixels);
  std::printf("CPU time: capture (ray casting + noise) %.0f ms; noise-free depth render %.0f ms\n", cpu_ms(t2, t3),
              cpu_ms(t3, t4));

  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  ccmap::tools::RgbImage img(depth.cols, depth.rows, 0);
  for (int r = 0; r < depth.rows; ++r) {
    for (int c = 0; c < depth.cols; ++c) {
      const float z = depth.at(c, r);
      std::uint8_t col[3] = {0, 0, 0};
      if (std::isfinite(z)) ccmap::tools::colormap_viridis(std::log(z / 0.3) / std::log(20.0 / 0.3), col);
      img.set(c, r, col);
    }
  }
  std::string error;
  const std::string depth_path = out + "/sim_depth.png";
  if (!ccmap::tools::write_png(depth_path, img, &error)) {
    std::fprintf(stderr, "%s\n", error.c_str());
    return 1;
  }
  // Top view: hillshade of the terrain with the measured points in red.
  const int n = 800;
  ccmap::tools::RgbImage top(n, n, 0);
  const double px = area.width() / n;
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) {
      const double x = area.x0 + (c + 0.5) * px, y = area.y1 - (r + 0.5) * px;
      const double e = 0.02;
      const double gx = (raster.height(x + e, y) - raster.height(x - e, y)) / (2 * e);
      const double gy = (raster.height(x, y + e) - raster.height(x, y - e)) / (2 * e);
      const double s = ccmap::tools::hillshade(gx, gy);
      const std::uint8_t g = static_cast<std::uint8_t>(std::lround(std::isfinite(s) ? 255.0 * s : 0.0));
      const std::uint8_t col[3] = {g, g, g};
      top.set(c, r, col);
    }
  }
  const std::uint8_t red[3] = {230, 40, 40};
  for (const auto& p : frame.points_map) {
    top.set(static_cast<int>((p.x - area.x0) / px), static_cast<int>((area.y1 - p.y) / px), red);
  }
  const std::string top_path = out + "/sim_topview.png";
  if (!ccmap::tools::write_png(top_path, top, &error)) {
    std::fprintf(stderr, "%s\n", error.c_str());
    return 1;
  }
  std::printf("wrote %s and %s\n", depth_path.c_str(), top_path.c_str());
  return 0;
}
