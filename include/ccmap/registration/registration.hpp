// Registration of a frame to the map before it is fused (the paper's future work, Section
// VIII: "pose estimate corrections based on the derived observation probabilities"):
// register_frame(stack, ...) (map-frame points and the sensor origin) and
// register_frame_sensor(stack, ...) (sensor-frame points and the pose), free functions over the
// stack as the planner queries are, return the rigid correction
// (registration/types.hpp says what it is, what is observable and what is claimed) and change
// nothing in the map. The caller applies the correction to its pose and then updates:
//
//   const ccmap::RegistrationResult c = ccmap::register_frame_sensor(map, points, n, pose, params);
//   if (c.status == ccmap::Status::kOk) { apply c to pose (registration/types.hpp) }
//   map.update_frame_sensor(points, n, pose, &counters);
//
// Method: point-to-distribution. Every k-th point (at most RegistrationParams::max_points) is
// matched against the plane and normal variance of the cell its range routes it to
// (registration/detail/stack_surface.hpp), with its sensor variance from the stack's noise
// model; robust Gauss-Newton over (dx, dy, dz, dyaw) in the observable subspace
// (registration/detail/solver.hpp). Not a point-cloud ICP: no nearest-neighbour search, no
// point of the map is stored; the cells' covariances are the map.
//
// Statuses (on any but kOk nothing is claimed: zero correction, infinite sigmas):
//   kNotInitialised      the stack is not initialised
//   kCorrupt             the stack's state failed its check (Stack::state_status: an upset)
//   kInvalidArgument     points == nullptr with n > 0; bad RegistrationParams; a pose whose
//                        rotation is not one (as update_frame_sensor)
//   kNonFiniteInput      a non-finite sensor origin or pose; every sampled point non-finite
//   kOutOfRange          a sensor origin beyond kMaxAbsCoordinateM
//   kDegenerateInput     no points, fewer than 3 usable, or all within one finest cell in x and y
//   kOutsideMap          the sensor origin outside the coarsest layer's window, most samples
//                        outside every window, or every usable sample beyond every layer's
//                        range (a pose far from the map)
//   kInsufficientOverlap fewer than min_matches samples on known cells
//   kNotConverged        no convergence within max_iterations, or a solution beyond
//                        max_translation_m / max_yaw_rad
// Cost: at most max_iterations passes over at most max_points samples, each a few cell reads
// and ~100 float operations; no heap, const (docs/performance.md gives instructions per call).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/map/stack.hpp"
#include "ccmap/map/types.hpp"
#include "ccmap/registration/detail/solver.hpp"
#include "ccmap/registration/detail/stack_surface.hpp"
#include "ccmap/registration/types.hpp"

namespace ccmap::detail {

/// Every k-th point of a frame as registration samples (map frame), with its routed layer and
/// its range variance from the stack's noise model.
template <typename Config>
class FrameSamples {
 public:
  using StackType = Stack<Config>;
  static constexpr int kLayers = StackType::kLayerCount;

  /// rotation: row-major 3 x 3 (sensor-frame points) or nullptr (map-frame points).
  FrameSamples(const StackType& stack, const PointXYZ* points, std::size_t n, const PointXYZ& origin,
               const float* rotation, std::uint32_t max_points) noexcept
      : stack_(stack), points_(points), n_(n), origin_(origin), rotation_(rotation) {
    const std::size_t cap = max_points > 0U ? max_points : 1U;
    stride_ = (n + cap - 1U) / cap;
    stride_ = stride_ > 0U ? stride_ : 1U;
    first_ = stride_ / 2U;
    for (int l = 0; l < kLayers; ++l) {
      max_range_sq_[l] = stack.layer_max_range_sq(l);
    }
  }

  template <typename Fn>
  SampleRefusals for_each(Fn&& fn) const noexcept {
    SampleRefusals refused{};
    const sensor::NoiseModel& noise = stack_.params().noise;
    for (std::size_t i = first_; i < n_; i += stride_) {
      const PointXYZ p = points_[i];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
        ++refused.non_finite;
        continue;
      }
      float x = 0.0F;
      float y = 0.0F;
      float z = 0.0F;
      float range_sq = 0.0F;
      if (rotation_ != nullptr) {
        // Sensor-frame coordinates of 2^11 m or more are refused, as by update_frame_sensor.
        constexpr float kMaxSensorM = 2048.0F;
        if (!(std::fabs(p.x) < kMaxSensorM && std::fabs(p.y) < kMaxSensorM && std::fabs(p.z) < kMaxSensorM)) {
          ++refused.out_of_reach;
          continue;
        }
        range_sq = p.x * p.x + p.y * p.y + p.z * p.z;
        const float* r = rotation_;
        x = r[0] * p.x + r[1] * p.y + r[2] * p.z + origin_.x;
        y = r[3] * p.x + r[4] * p.y + r[5] * p.z + origin_.y;
        z = r[6] * p.x + r[7] * p.y + r[8] * p.z + origin_.z;
      } else {
        if (!(std::fabs(p.x) <= kMaxAbsCoordinateM && std::fabs(p.y) <= kMaxAbsCoordinateM &&
              std::fabs(p.z) <= kMaxAbsCoordinateM)) {
          ++refused.out_of_reach;
          continue;
        }
        x = p.x;
        y = p.y;
        z = p.z;
        const float dx = x - origin_.x;
        const float dy = y - origin_.y;
        const float dz = z - origin_.z;
        range_sq = dx * dx + dy * dy + dz * dz;
      }
      int layer = -1;
      for (int l = 0; l < kLayers; ++l) {
        if (range_sq <= max_range_sq_[l]) {
          layer = l;
          break;
        }
      }
      if (layer < 0) {
        ++refused.out_of_reach;  // too noisy for every layer: the map would not take it either
        continue;
      }
      const float sigma = noise.sigma_at_range_sq(range_sq);
      fn(RegistrationSample{x, y, z, sigma * sigma, 0.0F, layer});
    }
    return refused;
  }

 private:
  const StackType& stack_;
  const PointXYZ* points_;
  std::size_t n_;
  PointXYZ origin_;
  const float* rotation_;
  std::size_t stride_ = 1U;
  std::size_t first_ = 0U;
  float max_range_sq_[static_cast<std::size_t>(kLayers > 0 ? kLayers : 1)]{};
};

/// register_frame and register_frame_sensor (below): `rotation` row-major 3 x 3, or nullptr for
/// map-frame points. Reads the stack through its public calls only.
template <typename Config>
[[nodiscard]] RegistrationResult register_points(const Stack<Config>& stack, const PointXYZ* points, std::size_t n,
                                                 const PointXYZ& origin, const float* rotation,
                                                 const RegistrationParams& params) noexcept {
  using StackType = Stack<Config>;
  const Status state = stack.state_status();  // kNotInitialised, or kCorrupt after an upset
  if (state != Status::kOk) {
    return unclaimed_result(state);
  }
  if (validate_registration_params(params) != Status::kOk || (points == nullptr && n > 0U)) {
    return unclaimed_result(Status::kInvalidArgument);
  }
  if (!std::isfinite(origin.x) || !std::isfinite(origin.y) || !std::isfinite(origin.z)) {
    return unclaimed_result(Status::kNonFiniteInput);
  }
  if (!(std::fabs(origin.x) <= kMaxAbsCoordinateM && std::fabs(origin.y) <= kMaxAbsCoordinateM &&
        std::fabs(origin.z) <= kMaxAbsCoordinateM)) {
    return unclaimed_result(Status::kOutOfRange);
  }
  if (rotation != nullptr) {
    const Status rotation_status = check_rotation(rotation);
    if (rotation_status != Status::kOk) {
      return unclaimed_result(rotation_status);
    }
  }
  // A pose far from the map: the stack is robot-centric, its coarsest window holds the robot.
  const int coarsest = StackType::kLayerCount - 1;
  CellIndex ignored{};
  const bool held = StackType::layer_is_ccm(coarsest) ? stack.ccm_layer(coarsest - StackType::kFineLayerCount).locate(origin.x, origin.y, &ignored)
                                                      : stack.fine_layer().locate(origin.x, origin.y, &ignored);
  if (!held) {
    return unclaimed_result(Status::kOutsideMap);
  }
  const FrameSamples<Config> samples(stack, points, n, origin, rotation, params.max_points);
  const StackSurface<Config> surface(stack);
  return solve_registration(samples, surface, origin.x, origin.y, origin.z, params, stack.layer_cell_width(0),
                            stack.layer_cell_width(StackType::kLayerCount - 1));
}

}  // namespace ccmap::detail

namespace ccmap {

/// The rigid correction (dx, dy, dz, dyaw about the vertical through sensor_origin) that best
/// aligns this frame's map-frame points with the map, with its standard deviations and which
/// of the four are observable (registration/types.hpp). Changes nothing in the map; the caller
/// applies it to its pose and then updates. Statuses: the file comment.
template <typename Config>
[[nodiscard]] RegistrationResult register_frame(const Stack<Config>& stack, const PointXYZ* points, std::size_t n,
                                                const PointXYZ& sensor_origin, const RegistrationParams& params) noexcept {
  return detail::register_points(stack, points, n, sensor_origin, nullptr, params);
}

/// The same for sensor-frame points with the sensor pose (rotation centre: the sensor position).
template <typename Config>
[[nodiscard]] RegistrationResult register_frame_sensor(const Stack<Config>& stack, const PointXYZ* points,
                                                       std::size_t n, const Pose& sensor_pose,
                                                       const RegistrationParams& params) noexcept {
  return detail::register_points(stack, points, n, sensor_pose.translation, &sensor_pose.rotation[0][0], params);
}

}  // namespace ccmap
