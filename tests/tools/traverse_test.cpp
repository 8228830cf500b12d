// CI check of the simulated CADRE traverse (tools/traverse) at its --quick size, in-process:
// 8 CADRE stereo frames (stride 4) along the start of the path, Stack<CadreConfig> updated in
// the sensor frame, final map judged against the hazard ground truth, the planner's look-ahead
// (query_path) after every frame.
#include <gtest/gtest.h>

#include "traverse/traverse.hpp"

namespace tr = ccmap::traverse;

namespace {

const tr::TraverseResult& quick_run() {
  static const tr::TraverseResult result = tr::run_traverse(tr::TraverseConfig::quick());
  return result;
}

void every_frame_updates_the_stack() {
  const tr::TraverseResult& r = quick_run();
  ASSERT_TRUE(r.ok()) << r.error;
  ASSERT_EQ(r.frames.size(), 8U);
  for (const tr::FrameRecord& f : r.frames) {
    EXPECT_TRUE(f.updated) << "frame " << f.index << " refused by update_frame_sensor";
    EXPECT_GT(f.points, 10000U) << "frame " << f.index << ": the camera saw almost nothing";
    EXPECT_GT(f.counters.used, f.points / 2) << "frame " << f.index << ": fewer than half the points were used";
    EXPECT_EQ(f.counters.rejected_non_finite + f.counters.rejected_out_of_range, 0U) << "frame " << f.index;
  }
  EXPECT_GT(r.update_ms_max, 0.0);
}

void exports_are_finite() {
  const tr::TraverseResult& r = quick_run();
  ASSERT_EQ(r.layers.size(), 5U);
  for (const tr::LayerReport& l : r.layers) {
    EXPECT_GT(l.exported, 0U) << "layer " << l.layer << " exported no cell";
    EXPECT_EQ(l.non_finite, 0U) << "layer " << l.layer << " exported " << l.non_finite << " cells with NaN/Inf";
  }
}

void large_obstacles_in_the_observed_area_are_detected() {
  const tr::TraverseResult& r = quick_run();
  // Objects at least 0.75 x the cell width of the layer that classifies them (the size each
  // layer is calibrated for), and the 48 cm class (the paper's 5 m-range minimum).
  ASSERT_GE(r.design_size.observed, 1) << "no obstacle of design size was observed: the scene is wrong";
  EXPECT_GE(r.design_size.rate(), 0.75) << r.design_size.detected << " of " << r.design_size.observed
                                        << " observed design-size obstacles detected";
  const tr::ObjectBin& large = r.large_objects();
  ASSERT_GE(large.observed, 1) << "no >= 48 cm rock observed";
  EXPECT_GE(large.rate(), 0.75) << large.detected << " of " << large.observed << " observed >= 48 cm rocks detected";
  // Area view: of the known ground-truth hazard area, the stack marks most as obstacle/steep.
  ASSERT_GT(r.stack.truth_hazard_known, 0.0);
  EXPECT_GE(r.stack.hit_share(), 0.75) << "stack marks only " << 100.0 * r.stack.hit_share()
                                       << " % of the known hazard area";
}

void few_false_obstacles_on_free_ground() {
  const tr::TraverseResult& r = quick_run();
  ASSERT_GT(r.stack.truth_free_known, 5.0) << "less than 5 m^2 of known free ground";
  EXPECT_LT(r.stack.false_share(), 0.05) << 100.0 * r.stack.false_share()
                                         << " % of the known free ground is marked obstacle/steep";
  for (const tr::LayerReport& l : r.layers) {
    EXPECT_LT(l.areas.false_share(), 0.05) << "layer " << l.layer << ": " << 100.0 * l.areas.false_share()
                                           << " % false obstacles on free ground";
  }
}

void the_look_ahead_runs_after_every_frame() {
  const tr::TraverseResult& r = quick_run();
  ASSERT_EQ(r.frames.size(), 8U);
  for (const tr::FrameRecord& f : r.frames) {
    EXPECT_TRUE(f.ahead_ok) << "frame " << f.index << ": the path query refused the look-ahead";
    EXPECT_GT(f.ahead_poses, 0U) << "frame " << f.index;
    // The route's corridor is cleared of rocks (0.45 m each side, the body is 0.4 m wide) and the
    // first 3.6 m are level lunar ground: nothing ahead is a hazard.
    EXPECT_FALSE(f.ahead_hazard) << "frame " << f.index << ": " << f.ahead_hazard_class << " at " << f.ahead_hazard_m
                                 << " m ahead on the cleared corridor";
  }
  // Before the rover has driven, its body's rear is unseen: the first look-ahead starts unknown;
  // once the camera has seen the ground under the body, it does not.
  EXPECT_TRUE(r.frames.front().ahead_unknown);
  EXPECT_NEAR(r.frames.front().ahead_unknown_m, 0.0, 1e-9);
  EXPECT_FALSE(r.frames.back().ahead_unknown);
  EXPECT_EQ(r.stop_frame, -1);
  EXPECT_GT(r.ahead_ms_max, 0.0);
}

}  // namespace

// One test, five checks: ctest runs every TEST in its own process, and the quick traverse
// (~9 s) would otherwise be simulated once per check.
TEST(ToolsTraverse, QuickTraverseUpdatesEveryFrameAndFindsTheHazards) {
  {
    SCOPED_TRACE("every frame updates the stack");
    every_frame_updates_the_stack();
  }
  {
    SCOPED_TRACE("exports are finite");
    exports_are_finite();
  }
  {
    SCOPED_TRACE("large obstacles in the observed area are detected");
    large_obstacles_in_the_observed_area_are_detected();
  }
  {
    SCOPED_TRACE("few false obstacles on free ground");
    few_false_obstacles_on_free_ground();
  }
  {
    SCOPED_TRACE("the look-ahead runs after every frame");
    the_look_ahead_runs_after_every_frame();
  }
}

TEST(ToolsTraverse, RegistrationTakesTheOdometryDriftOut) {
  // 3 % of the distance along 45 deg and 0.005 rad per metre of heading drift: the plain map is
  // fed poses that end centimetres off; registered, every frame's correction is carried on.
  ccmap::traverse::TraverseConfig cfg = ccmap::traverse::TraverseConfig::quick();
  cfg.drift_fraction = 0.03;
  cfg.yaw_drift_rad_per_m = 0.005;
  const ccmap::traverse::TraverseResult plain = ccmap::traverse::run_traverse(cfg);
  cfg.register_frames = true;
  const ccmap::traverse::TraverseResult registered = ccmap::traverse::run_traverse(cfg);
  ASSERT_TRUE(plain.ok() && registered.ok()) << plain.error << registered.error;
  EXPECT_GT(plain.final_pose_error_m, 0.04) << "the drift should show in the plain estimate";
  EXPECT_LT(registered.final_pose_error_m, 0.25 * plain.final_pose_error_m)
      << "registered " << registered.final_pose_error_m << " m against plain " << plain.final_pose_error_m << " m";
  std::size_t ok = 0;
  for (const ccmap::traverse::FrameRecord& f : registered.frames) ok += f.registration == "ok" ? 1U : 0U;
  EXPECT_GE(ok + 1U, registered.frames.size()) << "every frame after the first registered";
  EXPECT_TRUE(registered.frames.front().registration == "-") << "the first frame starts the map";
}
