#pragma once

// sin and cos without libm (bare metal has no vectorised one and the planner and registration
// need bitwise-equal answers on every target): defined in src/core/sin_cos.cpp.

namespace ccmap::detail {

/// sin and cos of theta, |theta| <= 7 rad (a full circle and a little): quadrant reduction with
/// a two-part pi/2, then polynomials on [-pi/4, pi/4]; error < 2e-7. + - * and floor only.
void sin_cos(float theta, float* sine, float* cosine) noexcept;

}  // namespace ccmap::detail
