#pragma once
// Piecewise-linear curves of time: activation a(t), displacement and force amplitudes.
//
// A curve is a list of points (t_i [s], v_i) with t strictly increasing. Between points the value
// is interpolated linearly; before the first point it holds v_0, after the last it holds v_last. An
// empty curve is the constant 1 (a load without a curve is applied at full value from t = 0).
// Curves are evaluated on the host once per step; backends receive the values, never the curves.
#include <algorithm>
#include <array>
#include <cstddef>
#include <vector>

namespace sinew::simulator {

struct Curve {
  std::vector<std::array<double, 2>> points;  // (t [s], value), t strictly increasing

  static Curve constant(double v) { return Curve{{{0.0, v}}}; }
  static Curve ramp(double t_end, double v_end) { return Curve{{{0.0, 0.0}, {t_end, v_end}}}; }

  double at(double t) const {
    if (points.empty()) return 1.0;
    if (t <= points.front()[0]) return points.front()[1];
    if (t >= points.back()[0]) return points.back()[1];
    const auto it =
        std::upper_bound(points.begin(), points.end(), t,
                         [](double x, const std::array<double, 2>& p) { return x < p[0]; });
    const auto& b = *it;
    const auto& a = *(it - 1);
    const double s = (t - a[0]) / (b[0] - a[0]);
    return a[1] + s * (b[1] - a[1]);
  }
  // Largest value the curve takes (the maximum over its points; 1 when empty).
  double max_value() const {
    if (points.empty()) return 1.0;
    double m = points.front()[1];
    for (const auto& p : points) m = std::max(m, p[1]);
    return m;
  }
  // True when t is strictly increasing.
  bool valid() const {
    for (std::size_t i = 1; i < points.size(); ++i)
      if (!(points[i][0] > points[i - 1][0])) return false;
    return true;
  }
};

}  // namespace sinew::simulator
