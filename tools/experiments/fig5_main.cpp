// ccmap_exp_fig5: CCM vs Kalman vs OMG precision and 3-sigma consistency (paper Fig. 5), on a
// simulated 20 x 20 m terrain and on the HiRISE Mars DTM (skipped when the data is absent).
//   ccmap_exp_fig5 [--seed N] [--out DIR] [--quick] [--paper-cell] [--data DIR]
//                  [--gate K] [--change-points M] [--change-share S]
// (the options of every experiment, common.hpp; ccmap_exp_fig5 --help lists them).
#include <cstdio>
#include <string>

#include "experiments/common.hpp"
#include "parse_args.hpp"
#include "experiments/fig5.hpp"
#include "sim/data_dir.hpp"
#include "sim/terrain.hpp"

int main(int argc, char** argv) {
  using namespace ccmap::experiments;
  ExperimentArgs args;
  const auto app = make_experiment_app(
      "ccmap_exp_fig5", "Fig. 5: CCM vs Kalman vs OMG reconstruction precision and variance (single-layer maps\n"
      "of cells: the gate options are accepted and unused)", &args);
  if (const int rc = parse_experiment_args(*app, argc, argv, &args); rc >= 0) return rc;
  Fig5Config cfg = args.quick ? Fig5Config::quick() : Fig5Config{};
  cfg.seed = args.seed;
  cfg.paper_cell = args.paper_cell;
  std::string error;
  if (!ensure_directory(args.out_dir, &error)) {
    std::fprintf(stderr, "error: %s\n", error.c_str());
    return 1;
  }

  const Fig5Run syn = run_fig5_synthetic(cfg, true);
  std::printf("Fig. 5, %s terrain, %zu points (%.0f /m^2, sigma_z %.2f m), evaluated every %.2f m, %s CCM cell\n\n%s\n",
              syn.terrain_name.c_str(), syn.points, cfg.points_per_m2, cfg.sigma_z_m, cfg.eval_step_m,
              cfg.paper_cell ? "paper (9-float)" : "full (10-float)",
              fig5_table(syn, true).c_str());
  const ccmap::sim::ProceduralTerrain terrain(fig5_terrain_params(cfg.size_m, cfg.seed));
  if (!write_fig5_images(syn, terrain, args.out_dir, "fig5", &error)) {
    std::fprintf(stderr, "error: %s\n", error.c_str());
    return 1;
  }
  const Fig5MethodStats* ccm = syn.find("CCM", cfg.cell_width_m);
  const Fig5MethodStats* omg = syn.find("OMG", cfg.cell_width_m);
  const Fig5MethodStats* ccm2 = syn.find("CCM", 2 * cfg.cell_width_m);
  std::printf("CCM / constant RMS ratio: %.2f (paper 0.07 / 0.15 = 0.47)\n", ccm->rms_m / omg->rms_m);
  std::printf("half resolution: CCM %.0f m RMS %.4f m in %zu B vs constant %.0f m RMS %.4f m in %zu B\n\n",
              ccm2->cell_width_m, ccm2->rms_m, ccm2->bytes, omg->cell_width_m, omg->rms_m, omg->bytes);

  Fig5Run mars;
  std::string why;
  if (run_fig5_mars(cfg, args.data_dir, true, &mars, &why)) {
    std::printf("Fig. 5 on real terrain: %s, %zu points (%.0f /m^2), evaluated every %.2f m\n\n%s\n",
                mars.terrain_name.c_str(), mars.points, cfg.mars_points_per_m2, cfg.mars_eval_step_m,
                fig5_table(mars, false).c_str());
    ccmap::sim::HeightRaster dtm;
    if (!ccmap::sim::load_esri_ascii(ccmap::sim::mars_dtm_path(args.data_dir), &dtm, &error)) {
      std::fprintf(stderr, "error: %s\n", error.c_str());
      return 1;
    }
    dtm.shift_heights(-dtm.mean_height());
    if (!write_fig5_images(mars, dtm, args.out_dir, "fig5_mars", &error)) {
      std::fprintf(stderr, "error: %s\n", error.c_str());
      return 1;
    }
  } else {
    std::printf("Mars DTM part skipped: %s\n\n", why.c_str());
  }
  std::printf("wrote %s/fig5_maps.svg (+ PNGs)%s\n", args.out_dir.c_str(),
              mars.methods.empty() ? "" : " and fig5_mars_maps.svg");
  return 0;
}
