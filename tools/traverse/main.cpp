// ccmap_traverse: the simulated CADRE traverse (the README's main job). A rover drives 13.5 m
// with a 90 deg turn over a generated lunar terrain, maps with Stack<CadreConfig> from a CADRE
// stereo frame every 0.3 m, and reports hazard detection against ground truth, update times
// and pictures. See traverse.hpp for the definitions.
//   ccmap_traverse [--seed N] [--out DIR] [--stride K] [--frames N] [--quick] [--paper-cell]
//                  [--mismatch P] [--gate K] [--change-points M] [--change-share S]
#include <cstdio>
#include <cstdlib>
#include <string>

#include "traverse/traverse.hpp"

namespace {

int usage(const char* argv0, std::FILE* f) {
  std::fprintf(f,
               "usage: %s [--seed N] [--out DIR] [--stride K] [--frames N] [--quick] [--paper-cell]\n"
               "       [--mismatch P] [--gate K] [--change-points M] [--change-share S]\n"
               "  --seed N    terrain and noise seed (default 1); results are deterministic by seed\n"
               "  --out DIR   pictures (default out/traverse)\n"
               "  --stride K  cast every K-th pixel of the 850 x 650 frame (default 1: full frame)\n"
               "  --frames N  stop after N frames (default: the whole 13.5 m path, 46 frames)\n"
               "  --quick     8 frames at stride 4 (what the CI test runs)\n"
               "  --paper-cell  the paper's 9-float CCM cell instead of the full cell (lateral covariance)\n"
               "  --mismatch P  stereo mismatches: a share P of the pixels at a random disparity (default 0)\n"
               "  --gate K, --change-points M, --change-share S\n"
               "              the map's outlier gate (K sigma, 0 = off: the paper's update) and change rule\n"
               "              (docs/design.md); default: the library's\n",
               argv0);
  return f == stdout ? 0 : 2;
}

}  // namespace

int main(int argc, char** argv) {
  ccmap::traverse::TraverseConfig cfg;
  cfg.out_dir = "out/traverse";
  std::uint64_t seed = 1;
  int stride = 0, frames = -1;
  bool quick = false, paper_cell = false;
  double mismatch = 0.0;
  ccmap::experiments::GateSetting gate;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const char* v = i + 1 < argc ? argv[i + 1] : nullptr;
    if (a == "--help" || a == "-h") return usage(argv[0], stdout);
    if (a == "--quick") {
      quick = true;
    } else if (a == "--paper-cell") {
      paper_cell = true;
    } else if (a == "--seed" && v != nullptr) {
      seed = std::strtoull(v, nullptr, 10);
      ++i;
    } else if (a == "--out" && v != nullptr) {
      cfg.out_dir = v;
      ++i;
    } else if (a == "--stride" && v != nullptr && std::atoi(v) >= 1) {
      stride = std::atoi(v);
      ++i;
    } else if (a == "--frames" && v != nullptr && std::atoi(v) >= 1) {
      frames = std::atoi(v);
      ++i;
    } else if ((a == "--mismatch" || a == "--gate" || a == "--change-points" || a == "--change-share") && v != nullptr &&
               std::strtod(v, nullptr) >= 0.0) {
      const double value = std::strtod(v, nullptr);
      (a == "--mismatch" ? mismatch
       : a == "--gate"   ? gate.sigma
       : a == "--change-points" ? gate.min_points
                                : gate.share) = value;
      ++i;
    } else {
      std::fprintf(stderr, "unknown or incomplete argument: %s\n", a.c_str());
      return usage(argv[0], stderr);
    }
  }
  if (quick) {
    const std::string out = cfg.out_dir;
    cfg = ccmap::traverse::TraverseConfig::quick();
    cfg.out_dir = out;
  }
  cfg.seed = seed;
  cfg.mismatch_share = mismatch;
  cfg.gate = gate;
  cfg.paper_cell = paper_cell;
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
