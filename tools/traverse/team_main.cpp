// ccmap_team: two or three simulated CADRE rovers map the traverse terrain along different
// paths and exchange deltas (include/ccmap/map/exchange.hpp); prints, per rover, the area its
// final map knows and the hazard area it finds, alone and with the team, and what it sent.
// See team.hpp for the definitions.
//   ccmap_team [--rovers 2|3] [--seed N] [--stride K] [--spacing M] [--every N] [--floor W]
//              [--finest LAYER] [--packet BYTES] [--out DIR] [--quick]
#include <cstdio>
#include <cstdlib>
#include <string>

#include "traverse/team.hpp"

namespace {

int usage(const char* argv0, std::FILE* f) {
  std::fprintf(f,
               "usage: %s [--rovers 2|3] [--seed N] [--stride K] [--spacing M] [--every N] [--floor W]\n"
               "          [--finest LAYER] [--packet BYTES] [--out DIR] [--quick]\n"
               "  --rovers N    2 or 3 rovers (default 3)\n"
               "  --seed N      terrain and noise seed (default 1); deterministic by seed\n"
               "  --stride K    cast every K-th pixel of the 850 x 650 frame (default 2)\n"
               "  --spacing M   metres driven between frames (default 0.3)\n"
               "  --every N     frames between exchanges (default 5)\n"
               "  --floor W     cells whose gain weighs less wait for a later delta (default 0)\n"
               "  --finest L    send layers L (0 = 4 cm) .. 4 (64 cm) only (default 0: all)\n"
               "  --packet B    largest delta in bytes (default: no limit); the rest waits\n"
               "  --out DIR     the picture (default out/team)\n"
               "  --quick       2 rovers, stride 8, a frame every 0.6 m, an exchange every 3 (the CI test)\n",
               argv0);
  return f == stdout ? 0 : 2;
}

bool positive(const char* v, double* out) {
  char* end = nullptr;
  const double d = std::strtod(v, &end);
  if (end == v || *end != '\0' || !(d > 0.0) || d > 1e9) return false;
  *out = d;
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  ccmap::traverse::TeamConfig cfg;
  std::string out_dir = "out/team";
  bool quick = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const char* v = i + 1 < argc ? argv[i + 1] : nullptr;
    double d = 0.0;
    if (a == "--help" || a == "-h") return usage(argv[0], stdout);
    if (a == "--quick") {
      quick = true;
      continue;
    }
    if (v == nullptr) {
      std::fprintf(stderr, "incomplete argument: %s\n", a.c_str());
      return usage(argv[0], stderr);
    }
    ++i;
    if (a == "--out") {
      out_dir = v;
    } else if (a == "--finest") {
      const int layer = std::atoi(v);
      if (layer < 0 || layer > 4 || std::string(v) != std::to_string(layer)) return usage(argv[0], stderr);
      cfg.finest_layer = layer;
    } else if (a == "--floor") {
      char* end = nullptr;
      const double w = std::strtod(v, &end);
      if (end == v || *end != '\0' || !(w >= 0.0) || w > 1e6) return usage(argv[0], stderr);
      cfg.weight_floor = static_cast<float>(w);
    } else if (!positive(v, &d)) {
      std::fprintf(stderr, "%s: '%s' is not a positive number\n", a.c_str(), v);
      return usage(argv[0], stderr);
    } else if (a == "--rovers") {
      cfg.rovers = static_cast<int>(d);
    } else if (a == "--seed") {
      cfg.seed = static_cast<std::uint64_t>(d);
    } else if (a == "--stride") {
      cfg.pixel_stride = static_cast<int>(d);
    } else if (a == "--spacing") {
      cfg.frame_spacing_m = d;
    } else if (a == "--every") {
      cfg.exchange_every = static_cast<int>(d);
    } else if (a == "--packet") {
      cfg.packet_bytes = static_cast<std::size_t>(d);
    } else {
      std::fprintf(stderr, "unknown argument: %s\n", a.c_str());
      return usage(argv[0], stderr);
    }
  }
  if (quick) {
    const ccmap::traverse::TeamConfig q = ccmap::traverse::TeamConfig::quick();
    cfg.rovers = q.rovers;
    cfg.pixel_stride = q.pixel_stride;
    cfg.frame_spacing_m = q.frame_spacing_m;
    cfg.exchange_every = q.exchange_every;
  }
  cfg.out_dir = out_dir;
  cfg.log = stdout;
  const ccmap::traverse::TeamResult result = ccmap::traverse::run_team(cfg);
  if (!result.ok()) {
    std::fprintf(stderr, "ccmap_team: %s\n", result.error.c_str());
    return 1;
  }
  std::printf("\n%s", ccmap::traverse::team_report(result, cfg).c_str());
  for (const std::string& p : result.pictures) std::printf("wrote %s\n", p.c_str());
  return 0;
}
