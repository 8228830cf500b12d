#include "ccmap/map/config.hpp"

namespace ccmap {

StackParams default_stack_params(float finest_cell_width_m) noexcept {
  StackParams p{};
  p.finest_cell_width_m = finest_cell_width_m;
  p.weight_limit = 1000.0F;
  p.coverage_tau = 0.8F;
  p.min_weight = 5.0F;
  p.obstacle_fraction = 0.75F;
  p.max_inclination = 0.36397023F;  // tan(20 deg)
  p.kalman_min_variance = kKalmanDefaultMinVariance;
  for (float& t : p.normal_variance_threshold) {
    t = 0.0F;
  }
  // The constant finest layer takes points while sigma_m <= its own IV-G bound
  // (sensor/noise_model.hpp, constant_layer_max_sigma, argues why).
  p.finest_max_sigma_m = sensor::constant_layer_max_sigma(finest_cell_width_m);
  // The outlier gate and change rule, chosen by measurement (docs/design.md, "Outlier gate
  // and change"; docs/evaluation.md, "Outliers").
  p.outlier_gate_sigma = 3.0F;
  p.change_min_points = 3.0F;
  p.change_share = 0.08F;
  // Free space from lines of sight, its ray count set by the budget: 256 lines of sight stay
  // inside the stage's 4 M aarch64 instructions per CADRE frame and the flight cycle's 43 M, 512
  // do not. docs/performance.md section 13 gives the cost, docs/evaluation.md what 256 rays do and
  // do not achieve against 128 and 512 (docs/design.md, "Free space from lines of sight").
  p.free_space_rays = 256.0F;
  p.free_space_clear_frames = 3.0F;
  p.sensor_view_axis = {0.0F, 0.0F, 0.0F};
  p.noise = sensor::cadre_stereo();
  return p;
}

}  // namespace ccmap
