// Every refusal status the public API answers, on the target: each bad input is answered with
// its Status, counted where the API counts it, and leaves the map bitwise unchanged
// (map_hash before and after). Points refused inside an accepted frame are counted by reason.
#include <cstdint>
#include <cstring>
#include <limits>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/cell/constant_cell.hpp"
#include "harness.hpp"
#include "shared_maps.hpp"
#include "support/map_state.hpp"

namespace {

using ccmap::PointXYZ;
using ccmap::Status;
using ccmap::bmtest::CadreStack;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

/// Stack 0, initialised, with one frame of terrain around the origin.
CadreStack& observed_stack() {
  CadreStack& s = ccmap::bmtest::cadre_stack(0);
  BM_CHECK(s.init(ccmap::default_stack_params(0.04F)) == Status::kOk, "init refused the CADRE defaults");
  ccmap::bmtest::terrain_frame(3, 0.0F, 0.0F, ccmap::bmtest::kFramePoints);
  BM_CHECK(s.update_frame(ccmap::bmtest::frame_map_points(), ccmap::bmtest::kFramePoints, PointXYZ{0.0F, 0.0F, 0.5F},
                          nullptr) == Status::kOk,
           "update_frame refused a valid frame");
  return s;
}

}  // namespace

BM_CASE(bad_input, calls_before_init_answer_not_initialised) {
  CadreStack& s = ccmap::bmtest::cadre_stack(1);
  ccmap::StackParams bad = ccmap::default_stack_params(0.04F);
  bad.finest_cell_width_m = -1.0F;
  BM_CHECK_STATUS(s.init(bad), Status::kInvalidArgument, "init with a negative cell width");
  const PointXYZ p{1.0F, 0.0F, 0.0F};
  BM_CHECK_STATUS(s.move_to(0.0F, 0.0F), Status::kNotInitialised, "move_to before init");
  BM_CHECK_STATUS(s.update_frame(&p, 1U, p, nullptr), Status::kNotInitialised, "update_frame before init");
  BM_CHECK_STATUS(s.query(0.0F, 0.0F).status, Status::kNotInitialised, "query before init");
  BM_CHECK_STATUS(s.query_layer(1, 0.0F, 0.0F).status, Status::kNotInitialised, "query_layer before init");
  ccmap::CellRecord record{};
  std::size_t written = 5U;
  BM_CHECK_STATUS(s.export_layer(0, &record, 1U, &written), Status::kNotInitialised, "export_layer before init");
  BM_CHECK_EQ(written, 0U, "export_layer wrote a count before init");
}

BM_CASE(bad_input, bad_parameters_are_refused_by_init) {
  CadreStack& s = ccmap::bmtest::cadre_stack(1);
  ccmap::StackParams p = ccmap::default_stack_params(0.04F);
  p.coverage_tau = kNaN;
  BM_CHECK_STATUS(s.init(p), Status::kNonFiniteInput, "init with a NaN tau");
  p = ccmap::default_stack_params(0.04F);
  p.weight_limit = 0.0F;
  BM_CHECK_STATUS(s.init(p), Status::kInvalidArgument, "init with a zero weight limit");
  BM_CHECK(!s.initialised(), "a refused init left the stack initialised");
}

BM_CASE(bad_input, refused_moves_and_frames_change_nothing_and_are_counted) {
  CadreStack& s = observed_stack();
  const std::uint64_t before = ccmap::test::map_hash(s);
  const std::uint32_t moves = s.rejected_moves();
  const std::uint32_t frames = s.rejected_frames();
  BM_CHECK_STATUS(s.move_to(kNaN, 0.0F), Status::kNonFiniteInput, "move_to(NaN)");
  BM_CHECK_STATUS(s.move_to(0.0F, kInf), Status::kNonFiniteInput, "move_to(Inf)");
  BM_CHECK_STATUS(s.move_to(2.0e5F, 0.0F), Status::kOutOfRange, "move_to beyond kMaxAbsCoordinateM");
  BM_CHECK_EQ(s.rejected_moves(), moves + 3U, "refused moves are not counted");

  PointXYZ* points = ccmap::bmtest::frame_map_points();
  ccmap::FrameCounters c{};
  BM_CHECK_STATUS(s.update_frame(nullptr, 10U, PointXYZ{0.0F, 0.0F, 0.5F}, &c), Status::kInvalidArgument,
                  "null points with n > 0");
  BM_CHECK_STATUS(s.update_frame(points, 10U, PointXYZ{kNaN, 0.0F, 0.5F}, &c), Status::kNonFiniteInput,
                  "NaN sensor origin");
  BM_CHECK_STATUS(s.update_frame(points, 10U, PointXYZ{0.0F, 0.0F, 2.0e5F}, &c), Status::kOutOfRange,
                  "sensor origin beyond kMaxAbsCoordinateM");
  ccmap::Pose pose{{{1.0F, 0.0F, 0.0F}, {0.0F, 1.0F, 0.0F}, {0.0F, 0.0F, 1.0F}}, PointXYZ{0.0F, 0.0F, 0.5F}};
  pose.rotation[1][0] = kInf;
  BM_CHECK_STATUS(s.update_frame_sensor(points, 10U, pose, &c), Status::kNonFiniteInput, "Inf in the rotation");
  BM_CHECK_EQ(c.received, 0U, "a refused frame reports received points");
  pose.rotation[1][0] = 0.5F;  // finite, but not a rotation (R^T R is not the identity)
  BM_CHECK_STATUS(s.update_frame_sensor(points, 10U, pose, &c), Status::kInvalidArgument, "a shear as the rotation");
  BM_CHECK_EQ(s.rejected_frames(), frames + 5U, "refused frames are not counted");
  BM_CHECK_EQ(ccmap::test::map_hash(s), before, "a refused call changed the map");
}

BM_CASE(bad_input, refused_points_are_counted_by_reason) {
  CadreStack& s = observed_stack();
  PointXYZ* points = ccmap::bmtest::frame_map_points();
  float weights[8] = {1.0F, 1.0F, 1.0F, 1.0F, 1.0F, 0.0F, -2.0F, kNaN};
  points[0] = PointXYZ{kNaN, 0.0F, 0.0F};
  points[1] = PointXYZ{0.0F, -kInf, 0.0F};
  points[2] = PointXYZ{0.3F, 0.0F, 3.0e5F};    // |z| beyond kMaxAbsCoordinateM
  points[3] = PointXYZ{300.0F, 0.0F, 0.0F};    // 300 m away: too noisy for every layer
  points[4] = PointXYZ{0.35F, 0.05F, 0.01F};   // valid
  points[5] = PointXYZ{0.35F, 0.05F, 0.01F};   // weight 0
  points[6] = PointXYZ{0.35F, 0.05F, 0.01F};   // negative weight
  points[7] = PointXYZ{0.35F, 0.05F, 0.01F};   // NaN weight
  ccmap::FrameCounters c{};
  BM_CHECK_STATUS(s.update_frame(points, weights, 8U, PointXYZ{0.0F, 0.0F, 0.5F}, &c), Status::kOk,
                  "a frame with bad points is still accepted");
  BM_CHECK_EQ(c.received, 8U, "received");
  BM_CHECK_EQ(c.rejected_non_finite, 2U, "NaN/Inf coordinates");
  BM_CHECK_EQ(c.rejected_out_of_range, 1U, "coordinates beyond kMaxAbsCoordinateM");
  BM_CHECK_EQ(c.too_noisy, 1U, "points too far for every layer (Section IV-G)");
  BM_CHECK_EQ(c.rejected_weight, 3U, "weights 0, negative, NaN");
  BM_CHECK_EQ(c.used, 1U, "the one valid point");
}

BM_CASE(bad_input, queries_and_exports) {
  CadreStack& s = observed_stack();
  BM_CHECK_STATUS(s.query(500.0F, 0.0F).status, Status::kOutsideMap, "query 500 m away");
  BM_CHECK_EQ(static_cast<std::uint32_t>(s.query(500.0F, 0.0F).layer + 1), 0U, "layer of an outside answer is not -1");
  BM_CHECK_STATUS(s.query_layer(0, 5.0F, 0.0F).status, Status::kOutsideMap, "outside the 4 cm layer's window");
  BM_CHECK_STATUS(s.query(-9.0F, -9.0F).status, Status::kUnknown, "an unobserved cell inside the 64 cm window");
  BM_CHECK_STATUS(s.query_layer(5, 0.0F, 0.0F).status, Status::kInvalidArgument, "layer 5 of a 5-layer stack");
  BM_CHECK_STATUS(s.query_layer(-1, 0.0F, 0.0F).status, Status::kInvalidArgument, "layer -1");
  ccmap::CellRecord records[4];
  std::size_t written = 7U;
  BM_CHECK_STATUS(s.export_layer(0, records, 4U, &written), Status::kBufferTooSmall, "export into 4 records");
  BM_CHECK_EQ(written, 0U, "a refused export wrote a count");
  BM_CHECK_STATUS(s.export_layer(9, records, 4U, &written), Status::kInvalidArgument, "export of layer 9");
  BM_CHECK_STATUS(s.export_layer(0, nullptr, 4096U, &written), Status::kInvalidArgument, "export into null");
}

BM_CASE(bad_input, cell_updates_refuse_and_leave_the_cell_unchanged) {
  ccmap::CcmCell cell{};
  BM_CHECK(ccmap::ccm_update(cell, 0.01F, 0.02F, 0.3F, 1.0F, 100.0F) == Status::kOk, "a valid update");
  const ccmap::CcmCell before = cell;
  BM_CHECK_STATUS(ccmap::ccm_update(cell, kNaN, 0.0F, 0.0F, 1.0F, 100.0F), Status::kNonFiniteInput, "NaN x");
  BM_CHECK_STATUS(ccmap::ccm_update(cell, 0.0F, 0.0F, 2.0e5F, 1.0F, 100.0F), Status::kOutOfRange, "z beyond 1e5 m");
  BM_CHECK_STATUS(ccmap::ccm_update(cell, 0.0F, 0.0F, 0.0F, 0.0F, 100.0F), Status::kBadWeight, "weight 0");
  BM_CHECK_STATUS(ccmap::ccm_update(cell, 0.0F, 0.0F, 0.0F, 2.0e6F, 100.0F), Status::kBadWeight, "weight 2e6");
  BM_CHECK_STATUS(ccmap::ccm_update(cell, 0.0F, 0.0F, 0.0F, 1.0F, 0.0F), Status::kInvalidArgument, "weight limit 0");
  BM_CHECK(std::memcmp(&cell, &before, sizeof cell) == 0, "a refused update changed the CCM cell");
  ccmap::KalmanCell kalman{};
  BM_CHECK_STATUS(ccmap::kalman_update(kalman, 0.1F, 0.0F), Status::kInvalidArgument, "measurement variance 0");
  BM_CHECK_STATUS(ccmap::kalman_update(kalman, kNaN, 1e-4F), Status::kNonFiniteInput, "NaN height");
  ccmap::OmgCell omg{};
  BM_CHECK_STATUS(ccmap::omg_update(omg, 0.1F, 1e-4F, -1.0F), Status::kBadWeight, "negative OMG weight");
  BM_CHECK(kalman.weight <= 0.0F && omg.weight <= 0.0F, "a refused update changed a constant cell");
}

BM_CASE(bad_input, status_names) {
  BM_CHECK(std::strcmp(ccmap::to_string(Status::kVersionMismatch), "version_mismatch") == 0,
           "to_string(kVersionMismatch)");
  BM_CHECK(std::strcmp(ccmap::to_string(static_cast<Status>(200)), "invalid_status") == 0,
           "to_string of a value outside the enum");
}
