#pragma once
// Error measures of the accuracy-versus-time study (bench/accuracy_study.cpp,
// docs/accuracy-vs-time.md): Richardson extrapolation of a converging sequence, the observed order
// of convergence, bilinear sampling of a nodal field on a lattice face, and relative vector-field
// errors. Header-only and free of the engine, so tests/bench/accuracy_measures_test.cpp checks
// them in milliseconds.
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

namespace sinew::accuracy {

// Richardson extrapolation from three solutions f_i on meshes of size h1 > h2 > h3 (any ratios),
// assuming f(h) = f* + C h^p:
//   (f1 − f2) / (f2 − f3) = (h1^p − h2^p) / (h2^p − h3^p)   solved for p by bisection on
//   [0.05, 12] (the right side increases monotonically in p for h1 > h2 > h3), then
//   C = (f2 − f3) / (h2^p − h3^p), f* = f3 − C h3^p.
// Source: Roache, "Verification and Validation in Computational Science and Engineering" (1998),
// §5.4 (generalised Richardson extrapolation, non-constant refinement ratio).
// ok = false when the differences do not have one sign (no monotone convergence: oscillating or
// round-off-dominated sequence), or p falls outside the bracket; value then is f3, order NaN.
struct Extrapolation {
  double value = 0;                                         // f*, the extrapolated h → 0 limit
  double order = std::numeric_limits<double>::quiet_NaN();  // p
  bool ok = false;
};

inline Extrapolation richardson(double h1, double f1, double h2, double f2, double h3, double f3) {
  Extrapolation out;
  out.value = f3;
  const double d12 = f1 - f2, d23 = f2 - f3;
  if (!(h1 > h2 && h2 > h3 && h3 > 0) || d23 == 0 || d12 * d23 <= 0) return out;
  const double target = d12 / d23;  // > 0
  auto ratio = [&](double p) {
    return (std::pow(h1, p) - std::pow(h2, p)) / (std::pow(h2, p) - std::pow(h3, p));
  };
  double lo = 0.05, hi = 12;
  if (target < ratio(lo) || target > ratio(hi)) return out;
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi);
    (ratio(mid) < target ? lo : hi) = mid;
  }
  const double p = 0.5 * (lo + hi);
  const double c = d23 / (std::pow(h2, p) - std::pow(h3, p));
  out.order = p;
  out.value = f3 - c * std::pow(h3, p);
  out.ok = true;
  return out;
}

// Observed order of convergence: the least-squares slope of log e against log h over the points
// with e > 0 (NaN with fewer than two). e ≈ C h^p gives p.
inline double observed_order(const std::vector<double>& h, const std::vector<double>& e) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  for (std::size_t i = 0; i < h.size() && i < e.size(); ++i) {
    if (!(e[i] > 0) || !(h[i] > 0)) continue;
    const double x = std::log(h[i]), y = std::log(e[i]);
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
    ++n;
  }
  if (n < 2) return std::numeric_limits<double>::quiet_NaN();
  const double den = n * sxx - sx * sx;
  if (den == 0) return std::numeric_limits<double>::quiet_NaN();
  return (n * sxy - sx * sy) / den;
}

// A vector field on a regular (nx + 1) × (ny + 1) node lattice of spacing h with its first node at
// (x0, y0) (one face of a voxel block, e.g. its top): values[i + (nx + 1) j], SI units of the field.
struct FaceField {
  int nx = 0, ny = 0;
  double x0 = 0, y0 = 0, h = 1;
  std::vector<std::array<double, 3>> values;
};

// Bilinear interpolation of the field at (x, y), clamped to the face. Exact for fields linear in x
// and y separately (a + b x + c y + d x y); at a node it returns that node's value.
inline std::array<double, 3> sample(const FaceField& f, double x, double y) {
  const double s = (x - f.x0) / f.h, t = (y - f.y0) / f.h;
  const double sc = std::fmin(std::fmax(s, 0.0), double(f.nx));
  const double tc = std::fmin(std::fmax(t, 0.0), double(f.ny));
  int i = int(std::floor(sc)), j = int(std::floor(tc));
  if (i >= f.nx) i = f.nx - 1;
  if (j >= f.ny) j = f.ny - 1;
  if (i < 0) i = 0;
  if (j < 0) j = 0;
  const double a = f.nx > 0 ? sc - i : 0, b = f.ny > 0 ? tc - j : 0;
  auto at = [&](int ii, int jj) {
    ii = ii > f.nx ? f.nx : ii;
    jj = jj > f.ny ? f.ny : jj;
    return f.values[std::size_t(ii + (f.nx + 1) * jj)];
  };
  const auto v00 = at(i, j), v10 = at(i + 1, j), v01 = at(i, j + 1), v11 = at(i + 1, j + 1);
  std::array<double, 3> out{};
  for (std::size_t k = 0; k < 3; ++k)
    out[k] =
        (1 - a) * (1 - b) * v00[k] + a * (1 - b) * v10[k] + (1 - a) * b * v01[k] + a * b * v11[k];
  return out;
}

// Relative errors of a vector field u against a reference r at the same points:
//   max_rel = max_i |u_i − r_i| / max_i |r_i|,  rms_rel = sqrt(mean_i |u_i − r_i|²) / max_i |r_i|
// (both normalised by the reference's largest magnitude, so small displacements far from the load
// do not inflate them). NaN when the reference is zero everywhere or the sizes differ.
struct FieldError {
  double max_rel = std::numeric_limits<double>::quiet_NaN();
  double rms_rel = std::numeric_limits<double>::quiet_NaN();
  double ref_max = 0;  // max_i |r_i|
};

inline FieldError field_error(const std::vector<std::array<double, 3>>& u,
                              const std::vector<std::array<double, 3>>& r) {
  FieldError out;
  if (u.size() != r.size() || r.empty()) return out;
  double emax = 0, esum = 0, rmax = 0;
  for (std::size_t i = 0; i < r.size(); ++i) {
    double d2 = 0, r2 = 0;
    for (std::size_t k = 0; k < 3; ++k) {
      d2 += (u[i][k] - r[i][k]) * (u[i][k] - r[i][k]);
      r2 += r[i][k] * r[i][k];
    }
    emax = std::fmax(emax, std::sqrt(d2));
    esum += d2;
    rmax = std::fmax(rmax, std::sqrt(r2));
  }
  out.ref_max = rmax;
  if (rmax == 0) return out;
  out.max_rel = emax / rmax;
  out.rms_rel = std::sqrt(esum / double(r.size())) / rmax;
  return out;
}

}  // namespace sinew::accuracy
