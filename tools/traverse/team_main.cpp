// ccmap_team: two or three simulated CADRE rovers map the traverse terrain along different
// paths and exchange deltas (include/ccmap/persistence/exchange.hpp); prints, per rover, the area its
// final map knows and the hazard area it finds, alone and with the team, and what it sent.
// See team.hpp for the definitions.
//   ccmap_team [--rovers 2|3] [--seed N] [--stride K] [--spacing M] [--every N] [--floor W]
//              [--finest LAYER] [--packet BYTES] [--out DIR] [--cells-only] [--quick]
// (ccmap_team --help lists them; a refused command line is one line on stderr and exit 2).
#include <cstdint>
#include <cstdio>
#include <string>

#include "number_options.hpp"
#include "parse_args.hpp"
#include "traverse/team.hpp"

int main(int argc, char** argv) {
  using ccmap::tools::add_real;
  using ccmap::tools::add_whole;
  ccmap::traverse::TeamConfig cfg;
  std::string out_dir = "out/team";
  bool quick = false;
  constexpr double kMax = 1e9;  // the largest count or length any option takes
  double weight_floor = cfg.weight_floor;
  CLI::App app("Two or three simulated CADRE rovers map the traverse terrain along different paths and\n"
               "exchange deltas; prints, per rover, the area its final map knows and the hazard area it\n"
               "finds, alone and with the team, and what it sent.",
               "ccmap_team");
  app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);  // as before: the last counts
  add_whole(app, "--rovers", &cfg.rovers, 1, static_cast<int>(kMax), "N", "2 or 3 rovers");
  add_whole<std::uint64_t>(app, "--seed", &cfg.seed, 1, static_cast<std::uint64_t>(kMax), "N",
                           "terrain and noise seed; deterministic by seed");
  add_whole(app, "--stride", &cfg.pixel_stride, 1, static_cast<int>(kMax), "K",
            "cast every K-th pixel of the 850 x 650 frame");
  add_real(app, "--spacing", &cfg.frame_spacing_m, 0.0, kMax, true, "M", "metres driven between frames");
  add_whole(app, "--every", &cfg.exchange_every, 1, static_cast<int>(kMax), "N", "frames between exchanges");
  add_real(app, "--floor", &weight_floor, 0.0, 1e6, false, "W",
           "cells whose gain weighs less wait for a later delta");
  add_whole(app, "--finest", &cfg.finest_layer, 0, 4, "L", "send layers L (0 = 4 cm) .. 4 (64 cm) only (0: all)");
  add_whole<std::size_t>(app, "--packet", &cfg.packet_bytes, 1, static_cast<std::size_t>(kMax), "B",
                         "largest delta in bytes (default: no limit); the rest waits")
      ->default_str("");
  app.add_option("--out", out_dir, "the picture")->type_name("DIR")->capture_default_str();
  bool cells_only = false;
  app.add_flag("--cells-only", cells_only, "merge every delta without its free-space entries (drop-offs, clears)");
  app.add_flag("--quick", quick, "2 rovers, stride 8, a frame every 0.6 m, an exchange every 3 (the CI test)");
  if (const int code = ccmap::tools::parse_args(app, argc, argv); code >= 0) return code;
  cfg.weight_floor = static_cast<float>(weight_floor);
  if (quick) {
    const ccmap::traverse::TeamConfig q = ccmap::traverse::TeamConfig::quick();
    cfg.rovers = q.rovers;
    cfg.pixel_stride = q.pixel_stride;
    cfg.frame_spacing_m = q.frame_spacing_m;
    cfg.exchange_every = q.exchange_every;
  }
  cfg.out_dir = out_dir;
  cfg.free_space_exchange = !cells_only;
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
