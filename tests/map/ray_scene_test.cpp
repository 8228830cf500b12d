// The free-space scenes' renderer (tests/support/ray_scene.hpp) keeps the casts of the last scene
// and pose and reuses them for the next frame of the same view: a frame rendered that way must be
// the frame a fresh render gives, bit for bit, and any change of the scene or the pose must cast
// again.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>

#include "support/ray_scene.hpp"

namespace ccmap {
namespace {

using test::AnalyticScene;
using test::SceneBox;
using test::SceneCamera;
using test::SceneDitch;
using test::SceneFrame;

bool same_frame(const SceneFrame& a, const SceneFrame& b) {
  return a.points.size() == b.points.size() &&
         std::memcmp(a.points.data(), b.points.data(), a.points.size() * sizeof(PointXYZ)) == 0 &&
         std::memcmp(&a.origin, &b.origin, sizeof(PointXYZ)) == 0;
}

// A frame of `scene` from `cam` cast afresh: another view rendered first evicts the kept casts.
SceneFrame fresh(const AnalyticScene& scene, const SceneCamera& cam) {
  AnalyticScene other;
  other.boxes.push_back(SceneBox{0.9, -2.0, 1.0, -1.9, 0.5});
  SceneCamera away = cam;
  away.x += 0.37;
  (void)test::render_scene(other, away);
  return test::render_scene(scene, cam);
}

AnalyticScene flank_and_ditch() {
  AnalyticScene s;
  s.slope_x = 0.05;
  for (int k = 0; k < 8; ++k) {
    s.boxes.push_back(SceneBox{1.5, 0.02 + 0.02 * k, 2.1, 0.52, 0.03 * (k + 1)});
  }
  s.ditches.push_back(SceneDitch{1.0, -0.8, 1.4, -0.2, 0.3});
  return s;
}

TEST(RayScene, AFrameFromKeptCastsIsTheFreshFrameBitForBit) {
  const AnalyticScene scene = flank_and_ditch();
  SceneCamera cam;
  cam.noise_per_range_sq = 1.0 / 300.0;
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    cam.seed = seed;
    const SceneFrame kept = test::render_scene(scene, cam);  // seed 1 casts, 2 to 4 reuse
    ASSERT_FALSE(kept.points.empty());
    EXPECT_TRUE(same_frame(kept, fresh(scene, cam))) << "seed " << seed;
    EXPECT_TRUE(same_frame(test::render_scene(scene, cam), kept)) << "seed " << seed << " again";
  }
  cam.seed = 1;
  cam.noise_per_range_sq = 0.0;  // the noise is not part of the casts either
  EXPECT_TRUE(same_frame(test::render_scene(scene, cam), fresh(scene, cam)));
}

TEST(RayScene, AnotherSceneOrPoseCastsAgain) {
  // Each change alone, each one the camera sees (every ray looks down: a low box's top and a
  // shallow ditch's floor are seen, a tall box's height or a deep ditch's depth would not be);
  // the frame after it must be that change's fresh frame, not the kept one.
  AnalyticScene scene;
  scene.slope_x = 0.02;
  scene.boxes.push_back(SceneBox{1.4, -0.15, 1.7, 0.15, 0.03});
  scene.boxes.push_back(SceneBox{1.2, 0.4, 1.3, 0.6, 0.02});
  scene.ditches.push_back(SceneDitch{2.0, -0.5, 2.6, 0.5, 0.02});
  SceneCamera cam;
  cam.noise_per_range_sq = 1.0 / 300.0;
  const SceneFrame base = fresh(scene, cam);
  const auto check = [&](const AnalyticScene& s, const SceneCamera& c, const char* what) {
    (void)test::render_scene(scene, cam);  // the base view's casts kept
    const SceneFrame after = test::render_scene(s, c);
    EXPECT_FALSE(same_frame(after, base)) << what << ": the change must change the frame";
    EXPECT_TRUE(same_frame(after, fresh(s, c))) << what;
  };
  AnalyticScene s = scene;
  s.boxes[0].height += 0.03;
  check(s, cam, "a box's height");
  s = scene;
  s.boxes[0].x1 += 0.2;
  check(s, cam, "a box's extent");
  s = scene;
  s.ditches[0].depth += 0.02;
  check(s, cam, "a ditch's depth");
  s = scene;
  s.boxes.pop_back();
  check(s, cam, "a box fewer");
  s = scene;
  s.slope_x = 0.0;
  check(s, cam, "the slope");
  SceneCamera c = cam;
  c.y += 0.05;
  check(scene, c, "the camera's position");
  c = cam;
  c.heading_cos = 0.9950041652780258;
  c.heading_sin = 0.09983341664682815;
  check(scene, c, "the camera's heading");
  c = cam;
  c.rows = 60;
  check(scene, c, "the camera's rows");
}

}  // namespace
}  // namespace ccmap
