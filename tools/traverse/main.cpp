// ccmap_traverse: the simulated CADRE traverse (the README's main job). A rover drives 13.5 m
// with a 90 deg turn over a generated lunar terrain, maps with Stack<CadreConfig> from a CADRE
// stereo frame every 0.3 m, and reports hazard detection against ground truth, update times
// and pictures. See traverse.hpp for the definitions.
//   ccmap_traverse [--seed N] [--out DIR] [--stride K] [--frames N] [--quick] [--paper-cell]
//                  [--mismatch P] [--gate K] [--change-points M] [--change-share S]
//                  [--drift F] [--drift-direction DEG] [--yaw-drift RAD_PER_M] [--register]
// (ccmap_traverse --help lists them; a refused command line is one line on stderr and exit 2).
#include <cstdint>
#include <cstdio>
#include <string>

#include "number_options.hpp"
#include "parse_args.hpp"
#include "traverse/traverse.hpp"

int main(int argc, char** argv) {
  ccmap::traverse::TraverseConfig cfg;
  cfg.out_dir = "out/traverse";
  std::uint64_t seed = 1;
  int stride = 0, frames = -1;  // 0, -1: the configuration's own (full frame, whole path; --quick: its values)
  bool quick = false, paper_cell = false;
  double mismatch = 0.0;
  ccmap::experiments::GateSetting gate;
  CLI::App app("The simulated CADRE traverse: a rover drives 13.5 m with a 90 deg turn over generated lunar\n"
               "terrain, maps with a CADRE stereo frame every 0.3 m and reports hazard detection against\n"
               "ground truth, update times and pictures.",
               "ccmap_traverse");
  app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);  // as before: the last counts
  ccmap::tools::add_whole<std::uint64_t>(app, "--seed", &seed, 0, UINT64_MAX, "N",
                                         "terrain and noise seed; results are deterministic by seed");
  app.add_option("--out", cfg.out_dir, "pictures")->type_name("DIR")->capture_default_str();
  ccmap::tools::add_whole(app, "--stride", &stride, 1, INT32_MAX, "K",
                          "cast every K-th pixel of the 850 x 650 frame (default 1: full frame)")
      ->default_str("");
  ccmap::tools::add_whole(app, "--frames", &frames, 1, INT32_MAX, "N",
                          "stop after N frames (default: the whole 13.5 m path, 46 frames)")
      ->default_str("");
  app.add_flag("--quick", quick, "8 frames at stride 4 (what the CI test runs)");
  app.add_flag("--paper-cell", paper_cell,
               "the paper's 9-float CCM cell instead of the full cell (lateral covariance)");
  ccmap::tools::add_real(app, "--mismatch", &mismatch, 0.0, 1.0, false, "P",
                         "stereo mismatches: a share P of the pixels at a random disparity");
  ccmap::experiments::add_gate_options(app, &gate);
  double drift = 0.0, drift_direction_deg = 45.0, yaw_drift = 0.0;
  bool register_frames = false;
  ccmap::tools::add_real(app, "--drift", &drift, 0.0, 1.0, false, "F",
                         "odometry drift: the pose estimate off by F x the distance driven (default 0)");
  ccmap::tools::add_real(app, "--drift-direction", &drift_direction_deg, -360.0, 360.0, false, "DEG",
                         "its direction in the map frame (default 45)");
  ccmap::tools::add_real(app, "--yaw-drift", &yaw_drift, -1.0, 1.0, false, "RAD_PER_M",
                         "odometry heading drift per metre driven (default 0)");
  app.add_flag("--register", register_frames,
               "register every frame after the first against the map before folding it in, and carry\n"
               "the correction in the pose estimate (register_frame_sensor(stack, ...))");
  if (const int code = ccmap::tools::parse_args(app, argc, argv); code >= 0) return code;
  if (quick) {
    const std::string out = cfg.out_dir;
    cfg = ccmap::traverse::TraverseConfig::quick();
    cfg.out_dir = out;
  }
  cfg.seed = seed;
  cfg.mismatch_share = mismatch;
  cfg.gate = gate;
  cfg.paper_cell = paper_cell;
  cfg.drift_fraction = drift;
  cfg.drift_direction_rad = drift_direction_deg * 3.14159265358979323846 / 180.0;
  cfg.yaw_drift_rad_per_m = yaw_drift;
  cfg.register_frames = register_frames;
  if (stride > 0) cfg.pixel_stride = stride;
  if (frames > 0) cfg.max_frames = frames;
  cfg.log = stdout;
  const ccmap::traverse::TraverseResult r = ccmap::traverse::run_traverse(cfg);
  if (!r.ok()) {
    std::fprintf(stderr, "ccmap_traverse: %s\n", r.error.c_str());
    return 1;
  }
  std::printf("\n%s\n", ccmap::traverse::traverse_report(r).c_str());
  for (const std::string& p : r.pictures) std::printf("wrote %s\n", p.c_str());
  return 0;
}
