// sin and cos without libm (core/sin_cos.hpp).
#include "ccmap/core/sin_cos.hpp"

#include <cmath>

namespace ccmap::detail {

void sin_cos(float theta, float* sine, float* cosine) noexcept {
  // theta = q pi/2 + r, |r| <= pi/4 (+ rounding); pi/2 in two parts (Cody-Waite, as fdlibm's
  // float reduction): kHalfPiHi has 17 significant bits, so q kHalfPiHi is exact for |q| <= 64
  // and theta - q kHalfPiHi is exact (Sterbenz); r carries the rounding of q kHalfPiLo (< 1e-11).
  constexpr float kTwoOverPi = 0.636619772F;
  constexpr float kHalfPiHi = 1.57078552F;     // 0x3FC90F80
  constexpr float kHalfPiLo = 1.08043341e-5F;  // 0x37354443: pi/2 - kHalfPiHi
  const float q = std::floor(theta * kTwoOverPi + 0.5F);
  const float r = (theta - q * kHalfPiHi) - q * kHalfPiLo;
  const float r2 = r * r;
  // Taylor series to r^9 and r^10: truncation below 2e-9 on |r| <= pi/4.
  const float s = r * (1.0F + r2 * (-1.0F / 6.0F + r2 * (1.0F / 120.0F + r2 * (-1.0F / 5040.0F + r2 * (1.0F / 362880.0F)))));
  const float c = 1.0F + r2 * (-0.5F + r2 * (1.0F / 24.0F + r2 * (-1.0F / 720.0F + r2 * (1.0F / 40320.0F + r2 * (-1.0F / 3628800.0F)))));
  const int quadrant = static_cast<int>(q) & 3;  // two's complement: -1 & 3 == 3
  switch (quadrant) {
    case 0: *sine = s; *cosine = c; break;
    case 1: *sine = c; *cosine = -s; break;
    case 2: *sine = -s; *cosine = -c; break;
    default: *sine = -c; *cosine = s; break;
  }
}

}  // namespace ccmap::detail
