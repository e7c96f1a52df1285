#pragma once
/// atan2 within 2e-6 rad, several times cheaper than std::atan2, for passes that take tens of
/// millions of angles and round them to quarter turns or sum them around fans (the field's
/// singularities, the map's wound vertices). Internal.
#include <algorithm>
#include <cmath>

namespace seamvox::detail {

/// Octant reduction and an odd polynomial of degree 11 for atan on [0, 1]. (0, 0) gives 0; a
/// straight angle (y = 0, x < 0) gives pi whatever the sign of the zero.
inline double fastAtan2(double y, double x) {
  const double ax = std::abs(x), ay = std::abs(y);
  const double big = std::max(ax, ay);
  if (big == 0.0) return 0.0;
  const double a = std::min(ax, ay) / big, s = a * a;
  double r = a * (0.99997726 + s * (-0.33262347 + s * (0.19354346 + s * (-0.11643287 + s * (0.05265332 - s * 0.0117212)))));
  if (ay > ax) r = 1.5707963267948966 - r;
  if (x < 0.0) r = 3.141592653589793 - r;
  return y < 0.0 ? -r : r;
}

}  // namespace seamvox::detail
