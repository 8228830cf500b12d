// Registration on the target (registration/registration.hpp): the 4 x 4 algebra (Eigen's
// fixed-size float types, src/registration/detail/normal_equations.cpp) linked into a board image, so
// that the image checks (no heap, no soft double, no exception tables) cover it. Two small CADRE
// frames: the map from the first, the second registered with its heights 2 cm low.
#include <cstddef>
#include <cstdint>
#include <limits>

#include "ccmap/registration/registration.hpp"
#include "harness.hpp"
#include "shared_maps.hpp"
#include "support/cadre_frames.hpp"

namespace {

using ccmap::PointXYZ;
using ccmap::Status;

/// The map of a 125 x 80 px CADRE frame from the origin; the next frame, 0.25 m ahead, in
/// frame_map_points() with its heights lowered by 2 cm (a pose 2 cm too low); its origin in *origin.
ccmap::bmtest::CadreStack& mapped(PointXYZ* origin) {
  ccmap::bmtest::CadreStack& s = ccmap::bmtest::cadre_stack(0);
  BM_CHECK(s.init(ccmap::default_stack_params(0.04F)) == Status::kOk, "init refused the CADRE defaults");
  ccmap::test::CadreFrameSpec spec;
  spec.width_px = 125;
  spec.height_px = 80;
  ccmap::Pose pose{};
  ccmap::test::fill_cadre_frame(spec, ccmap::bmtest::frame_map_points(), ccmap::bmtest::frame_sensor_points(), origin,
                                &pose);
  BM_CHECK(s.update_frame_sensor(ccmap::bmtest::frame_sensor_points(), ccmap::bmtest::kFramePoints, pose, nullptr) ==
               Status::kOk,
           "the first frame was refused");
  spec.sensor_x = 0.25F;
  spec.seed = 2U;
  ccmap::test::fill_cadre_frame(spec, ccmap::bmtest::frame_map_points(), ccmap::bmtest::frame_sensor_points(), origin,
                                &pose);
  PointXYZ* points = ccmap::bmtest::frame_map_points();
  for (std::size_t i = 0; i < ccmap::bmtest::kFramePoints; ++i) {
    points[i].z -= 0.02F;
  }
  BM_CHECK(s.move_to(0.25F, 0.0F) == Status::kOk, "move refused");
  return s;
}

}  // namespace

BM_CASE(registration, a_frame_two_centimetres_low_is_corrected) {
  PointXYZ origin{};
  const ccmap::bmtest::CadreStack& s = mapped(&origin);
  const ccmap::RegistrationResult r = ccmap::register_frame(s, ccmap::bmtest::frame_map_points(), ccmap::bmtest::kFramePoints,
                                                       origin, ccmap::default_registration_params());
  BM_CHECK_STATUS(r.status, Status::kOk, "registration of a frame 2 cm low");
  BM_CHECK(r.observable[ccmap::kAxisZ], "the height was not observable");
  BM_CHECK_NEAR(r.dz, 0.02F, 0.003F, "height correction of a frame 2 cm low");
  BM_CHECK(r.sigma_dz < 0.002F, "height sigma above 2 mm");
  BM_CHECK(r.iterations <= ccmap::default_registration_params().max_iterations, "more iterations than allowed");
}

BM_CASE(registration, refusals_claim_nothing) {
  PointXYZ origin{};
  const ccmap::bmtest::CadreStack& s = mapped(&origin);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const ccmap::RegistrationParams p = ccmap::default_registration_params();
  ccmap::RegistrationResult r = ccmap::register_frame(s, ccmap::bmtest::frame_map_points(), ccmap::bmtest::kFramePoints,
                                                 PointXYZ{nan, 0.0F, 0.2F}, p);
  BM_CHECK_STATUS(r.status, Status::kNonFiniteInput, "a NaN sensor origin");
  BM_CHECK(!r.observable[ccmap::kAxisZ] && ccmap::bmtest::bits(r.dz) == 0U, "a refusal claimed a height");
  r = ccmap::register_frame(s, ccmap::bmtest::frame_map_points(), 0U, origin, p);
  BM_CHECK_STATUS(r.status, Status::kDegenerateInput, "no points");
  r = ccmap::register_frame(s, ccmap::bmtest::frame_map_points(), ccmap::bmtest::kFramePoints, PointXYZ{60.0F, 0.0F, 0.2F}, p);
  BM_CHECK_STATUS(r.status, Status::kOutsideMap, "a pose far from the map");
}
