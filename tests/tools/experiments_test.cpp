// CI checks of the paper experiments at reduced size (--quick configurations, in-process).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "experiments/fig4.hpp"
#include "experiments/fig5.hpp"
#include "experiments/lateral.hpp"
#include "ccmap/cell/ccm_cell.hpp"
#include "experiments/svg_plot.hpp"
#include "sim/data_dir.hpp"

namespace ex = ccmap::experiments;

TEST(ExperimentsFig4, NoiselessThresholdAndIntervalMatchAnalytic) {
  const ex::Fig4Config cfg = ex::Fig4Config::quick();
  const ex::Fig4Result r = ex::run_fig4(cfg);
  const double h2_16 = cfg.step_height_m * cfg.step_height_m / 16.0;
  EXPECT_NEAR(r.threshold, h2_16, 0.05 * h2_16) << "50 % coverage threshold " << r.threshold * 1e4
                                                 << " cm^2 is not h^2/16 = " << h2_16 * 1e4 << " cm^2";
  // Analytic interval: c (1 - c) >= 1/12, i.e. 9.18 % - 90.82 % (paper: 11 % - 91 %).
  EXPECT_NEAR(r.interval.lo, 0.0918, 0.02) << "lower detected coverage " << r.interval.lo;
  EXPECT_NEAR(r.interval.hi, 0.9082, 0.02) << "upper detected coverage " << r.interval.hi;
  EXPECT_NEAR(r.analytic_interval.lo, 0.0918, 1e-3);
  // The curve is h^2 u (1 - 3u): check it point by point on the grid.
  for (std::size_t k = 0; k < r.noiseless.coverage.size(); k += 10) {
    const double c = r.noiseless.coverage[k];
    EXPECT_NEAR(r.noiseless.normal_variance[k], ex::fig4_analytic_normal_variance(c, cfg.step_height_m), 0.02 * h2_16)
        << "normal variance off the analytic curve at coverage " << c;
  }
  ASSERT_EQ(r.noisy.size(), cfg.noisy_ranges_m.size());
  for (const ex::Fig4NoisyCurve& nc : r.noisy) {
    EXPECT_TRUE(std::isfinite(nc.interval.lo) && nc.interval.lo < 0.5 && nc.interval.hi > 0.5)
        << "noisy curve at " << nc.range_m << " m detects no obstacle around 50 % coverage";
  }
}

TEST(ExperimentsFig4, DeterministicBySeed) {
  ex::Fig4Config cfg = ex::Fig4Config::quick();
  cfg.grid_n = 20;
  const ex::Fig4Result a = ex::run_fig4(cfg), b = ex::run_fig4(cfg);
  ASSERT_EQ(a.noisy.size(), b.noisy.size());
  for (std::size_t i = 0; i < a.noisy.size(); ++i) {
    EXPECT_EQ(a.noisy[i].curve.normal_variance, b.noisy[i].curve.normal_variance);
  }
}

TEST(ExperimentsFig5, CcmBeatsConstantMapsAndKalmanFailsThreeSigma) {
  const ex::Fig5Config cfg = ex::Fig5Config::quick();
  const ex::Fig5Run run = ex::run_fig5_synthetic(cfg, false);
  const ex::Fig5MethodStats* ccm = run.find("CCM", cfg.cell_width_m);
  const ex::Fig5MethodStats* omg = run.find("OMG", cfg.cell_width_m);
  const ex::Fig5MethodStats* kal = run.find("Kalman", cfg.cell_width_m);
  const ex::Fig5MethodStats* ccm2 = run.find("CCM", 2.0 * cfg.cell_width_m);
  ASSERT_TRUE(ccm && omg && kal && ccm2);
  EXPECT_EQ(ccm->cells_x, 7) << "20 m / 3 m cells";
  EXPECT_GT(ccm->samples, 30000U);
  EXPECT_LT(ccm->rms_m, 0.7 * omg->rms_m) << "CCM RMS " << ccm->rms_m << " m vs constant " << omg->rms_m << " m";
  // Kalman with constant R from its first measurement is the running mean, as is OMG with
  // constant weights: identical heights up to float rounding.
  EXPECT_NEAR(kal->rms_m, omg->rms_m, 1e-4 * omg->rms_m) << "Kalman and OMG heights differ";
  EXPECT_GT(kal->violation_share, 0.5) << "Kalman variance should ignore the sample spread";
  EXPECT_GT(kal->violation_share, 5.0 * omg->violation_share + 0.2);
  EXPECT_GT(kal->violation_share, 5.0 * ccm->violation_share + 0.2);
  EXPECT_LT(ccm->violation_share, 0.05) << "CCM variance should bound its error";
  // Half resolution: CCM at 2w in about the memory of a constant map at w.
  EXPECT_EQ(ccm2->bytes, 16U * sizeof(ccmap::CcmCell));  // 40 B: the full cell
  EXPECT_EQ(omg->bytes, 49U * 12U);
  EXPECT_LT(ccm2->rms_m, 1.3 * omg->rms_m) << "CCM at 2w should be about as precise as constant maps at w";
}

TEST(ExperimentsFig5, MarsDtmCcmMorePrecise) {
  const ex::Fig5Config cfg = ex::Fig5Config::quick();
  ex::Fig5Run run;
  std::string why;
  if (!ex::run_fig5_mars(cfg, ccmap::sim::resolve_data_dir(), false, &run, &why)) GTEST_SKIP() << why;
  const ex::Fig5MethodStats* ccm = run.find("CCM", cfg.mars_cell_width_m);
  const ex::Fig5MethodStats* omg = run.find("OMG", cfg.mars_cell_width_m);
  const ex::Fig5MethodStats* kal = run.find("Kalman", cfg.mars_cell_width_m);
  ASSERT_TRUE(ccm && omg && kal);
  EXPECT_LT(ccm->rms_m, 0.7 * omg->rms_m) << "on the Mars DTM";
  EXPECT_GT(kal->violation_share, 0.5);
}

TEST(ExperimentsSvg, NiceTicksAndWellFormedOutput) {
  const std::vector<double> t = ex::nice_ticks(0.0, 0.93, 5);
  ASSERT_GE(t.size(), 4U);
  EXPECT_NEAR(t[1] - t[0], 0.2, 1e-12);
  ex::SvgPlot p;
  p.title = "a < b";
  p.series.push_back(ex::SvgSeries{"s", {0, 1, 2}, {0, 1, 4}, "", false, true, 2.0});
  const std::string svg = ex::render_svg(p);
  EXPECT_NE(svg.find("<svg"), std::string::npos);
  EXPECT_NE(svg.find("a &lt; b"), std::string::npos) << "title must be escaped";
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
}

TEST(ExperimentsLateral, FullCellSlopesAreExactWhereThePaperCellLeaks) {
  const ex::LateralConfig cfg = ex::LateralConfig::quick();
  const ex::LateralResult r = ex::run_lateral(cfg);
  ASSERT_EQ(r.slopes.size(), 8U);
  for (const ex::LateralSlopeRow& s : r.slopes) {
    EXPECT_LT(s.full_max, 1e-4) << "full cell slope error on " << s.name;
  }
  EXPECT_NEAR(r.slopes[0].paper_slope_x, -0.5 * std::tan(12.0 * M_PI / 180.0), 0.005)
      << "paper cell on the diagonal half: slope_x should be -b/2";
  EXPECT_GT(r.slopes[1].paper_rms, 0.03) << "paper cell on random half cells";
  EXPECT_EQ(r.slopes[0].full_covered, 0) << "a diagonal half cell is not covered";
  EXPECT_EQ(r.slopes[0].paper_covered, 1) << "the paper cell's per-axis test passes a diagonal half";
  ASSERT_EQ(r.coverage.size(), 4U);
  EXPECT_NEAR(r.coverage[0].full_share, 0.80, 0.005) << "an axis-aligned edge needs tau of the cell seen";
  EXPECT_NEAR(r.coverage[0].paper_share, 0.80, 0.005);
  for (const ex::LateralCoverageRow& c : r.coverage) {
    EXPECT_GE(c.full_share, 0.795) << "full cell at " << c.edge_deg << " deg";
  }
  EXPECT_LT(r.coverage[3].paper_share, 0.55) << "the paper cell passes half a cell cut at 45 deg";
}
