#include "sinew/postprocess/wrinkles.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

#include "sinew/common/error.hpp"
#include "sinew/common/log.hpp"

namespace sinew::postprocess {
namespace {

using V3 = std::array<double, 3>;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr std::size_t kMinSamples = 16;

V3 sub(const V3& a, const V3& b) {
  return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
V3 cross(const V3& a, const V3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double dot(const V3& a, const V3& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
double norm(const V3& a) {
  return std::sqrt(dot(a, a));
}

V3 vertex(const std::vector<float>& p, std::int32_t i) {
  const auto k = 3 * static_cast<std::size_t>(i);
  return {p[k], p[k + 1], p[k + 2]};
}

void check_options(const WrinkleOptions& o) {
  auto bad = [](const char* field, const std::string& problem) {
    return ConfigError("", field, problem);
  };
  if (o.up < 0 || o.up > 2) throw bad("up", "must be an axis 0, 1 or 2 (x, y, z)");
  if (o.across < 0 || o.across > 2) throw bad("across", "must be an axis 0, 1 or 2 (x, y, z)");
  if (o.up == o.across) throw bad("across", "must differ from the up axis");
  if (o.profiles < 1 || o.profiles > 100000) throw bad("profiles", "must be in [1, 100000]");
  if (!(o.detrend_width > 0) || !std::isfinite(o.detrend_width)) {
    throw bad("detrend_width", "must be a finite length > 0");
  }
  if (!(o.min_depth > 0) || !std::isfinite(o.min_depth)) {
    throw bad("min_depth", "must be a finite length > 0");
  }
  if (!(o.spacing >= 0) || !std::isfinite(o.spacing)) {
    throw bad("spacing", "must be a finite length ≥ 0 (0: automatic)");
  }
  if (!(o.min_facing > 0 && o.min_facing <= 1)) throw bad("min_facing", "must be in (0, 1]");
  if (!(o.voxel_size >= 0) || !std::isfinite(o.voxel_size)) {
    throw bad("voxel_size", "must be a finite length ≥ 0 (0: unknown)");
  }
  for (double c : o.lattice_origin) {
    if (!std::isfinite(c)) throw bad("lattice_origin", "must be finite");
  }
  if (o.region) {
    const auto& r = *o.region;
    for (int a = 0; a < 3; ++a) {
      if (!std::isfinite(r[2 * a]) || !std::isfinite(r[2 * a + 1]) || !(r[2 * a] < r[2 * a + 1])) {
        throw bad("region", fmt::format("axis {}: min must be < max (both finite)", "xyz"[a]));
      }
    }
  }
}

void check_arrays(const std::vector<std::int32_t>& tri, const std::vector<float>& rest,
                  const std::vector<float>& def, const std::string& file) {
  if (rest.size() % 3 != 0 || rest.empty()) {
    throw FormatError(file, "rest", "positions must be a non-empty V × 3 array");
  }
  if (def.size() != rest.size()) {
    throw FormatError(
        file, "positions",
        fmt::format("the frame has {} values, the rest pose {}", def.size(), rest.size()));
  }
  if (tri.size() % 3 != 0 || tri.empty()) {
    throw FormatError(file, "triangles", "must be a non-empty T × 3 array");
  }
  const auto v = static_cast<std::int64_t>(rest.size() / 3);
  for (std::size_t i = 0; i < tri.size(); ++i) {
    if (tri[i] < 0 || tri[i] >= v) {
      throw FormatError(file, "triangles",
                        fmt::format("vertex id {} out of range [0, {})", tri[i], v))
          .at(static_cast<std::int64_t>(i / 3));
    }
  }
  for (std::size_t i = 0; i < rest.size(); ++i) {
    if (!std::isfinite(rest[i])) {
      throw FormatError(file, "rest", "non-finite position").at(static_cast<std::int64_t>(i / 3));
    }
    if (!std::isfinite(def[i])) {
      throw FormatError(file, "positions", "non-finite position")
          .at(static_cast<std::int64_t>(i / 3));
    }
  }
}

// The upper median of v (v.size() / 2 in sorted order); NaN when v is empty.
double upper_median(std::vector<double> v) {
  if (v.empty()) return kNaN;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

double median_edge(const std::vector<std::int32_t>& tri, const std::vector<float>& rest) {
  std::vector<double> e;
  e.reserve(tri.size());
  for (std::size_t t = 0; t < tri.size(); t += 3) {
    for (int k = 0; k < 3; ++k) {
      e.push_back(norm(sub(vertex(rest, tri[t + k]), vertex(rest, tri[t + (k + 1) % 3]))));
    }
  }
  return upper_median(std::move(e));
}

// Area-weighted vertex normals (unnormalised sums of the triangles' cross products).
std::vector<V3> vertex_normals(const std::vector<std::int32_t>& tri, const std::vector<float>& p) {
  std::vector<V3> n(p.size() / 3, V3{0, 0, 0});
  for (std::size_t t = 0; t < tri.size(); t += 3) {
    const auto a = vertex(p, tri[t]), b = vertex(p, tri[t + 1]), c = vertex(p, tri[t + 2]);
    const auto f = cross(sub(b, a), sub(c, a));
    for (int k = 0; k < 3; ++k) {
      auto& m = n[static_cast<std::size_t>(tri[t + k])];
      for (int i = 0; i < 3; ++i) m[i] += f[i];
    }
  }
  return n;
}

// One sample point of a profile: its triangle and barycentric coordinates.
struct Hit {
  bool valid = false;
  double height = -std::numeric_limits<double>::infinity();
  std::size_t triangle = 0;
  V3 bary{0, 0, 0};
};

// Zigzag fold detection on r (see the header).
void find_folds(WrinkleProfile& p, double delta, int up) {
  const auto& r = p.residual;
  const std::size_t n = r.size();
  struct Ext {
    std::size_t i;
    bool crest;
  };
  std::vector<Ext> ext;
  int trend = 0;  // 0 unknown, +1 rising (looking for a crest), −1 falling
  std::size_t hi_i = 0, lo_i = 0;
  for (std::size_t j = 1; j < n; ++j) {
    if (trend == 0) {
      if (r[j] > r[hi_i]) hi_i = j;
      if (r[j] < r[lo_i]) lo_i = j;
      if (r[j] <= r[hi_i] - delta) {
        ext.push_back({hi_i, true});
        trend = -1;
        lo_i = j;
      } else if (r[j] >= r[lo_i] + delta) {
        ext.push_back({lo_i, false});
        trend = 1;
        hi_i = j;
      }
    } else if (trend < 0) {
      if (r[j] < r[lo_i]) {
        lo_i = j;
      } else if (r[j] >= r[lo_i] + delta) {
        ext.push_back({lo_i, false});
        trend = 1;
        hi_i = j;
      }
    } else {
      if (r[j] > r[hi_i]) {
        hi_i = j;
      } else if (r[j] <= r[hi_i] - delta) {
        ext.push_back({hi_i, true});
        trend = -1;
        lo_i = j;
      }
    }
  }
  // The pending crest after the last confirmed trough (rose by ≥ δ, not yet fallen by δ).
  if (trend > 0) ext.push_back({hi_i, true});
  auto interior = [&](std::size_t i) { return i > 0 && i + 1 < n; };
  for (std::size_t k = 1; k + 1 < ext.size(); ++k) {
    if (ext[k].crest || !ext[k - 1].crest || !ext[k + 1].crest) continue;
    const auto l = ext[k - 1].i, t = ext[k].i, rr = ext[k + 1].i;
    if (!interior(l) || !interior(rr)) continue;
    Fold f;
    f.s = p.s[t];
    f.arc = p.arc[t];
    f.residual = r[t];
    f.depth = 0.5 * ((r[l] - r[t]) + (r[rr] - r[t]));
    f.height = p.rest[3 * t + static_cast<std::size_t>(up)];
    p.folds.push_back(f);
  }
}

// Peak of the Hann-windowed periodogram of r over wavelengths [lmin, lmax] (rest arc length).
double spectral_peak(const std::vector<double>& s, const std::vector<double>& r, double lmin,
                     double lmax) {
  const std::size_t n = s.size();
  const double length = s.back() - s.front();
  if (!(lmax > lmin) || length <= 0) return kNaN;
  // Uniform resampling by linear interpolation.
  std::vector<double> u(n);
  const double ds = length / static_cast<double>(n - 1);
  std::size_t i = 0;
  double mean = 0;
  for (std::size_t j = 0; j < n; ++j) {
    const double t = s.front() + ds * static_cast<double>(j);
    while (i + 2 < n && s[i + 1] < t) ++i;
    const double w = std::clamp((t - s[i]) / (s[i + 1] - s[i]), 0.0, 1.0);
    u[j] = (1 - w) * r[i] + w * r[i + 1];
    mean += u[j];
  }
  mean /= static_cast<double>(n);
  for (std::size_t j = 0; j < n; ++j) {
    const double hann =
        0.5 * (1 - std::cos(2 * std::numbers::pi * static_cast<double>(j) / (n - 1.0)));
    u[j] = (u[j] - mean) * hann;
  }
  const double kmin = 2 * std::numbers::pi / lmax, kmax = 2 * std::numbers::pi / lmin;
  const double dk = 2 * std::numbers::pi / length / 8;  // 8 × zero padding
  double best = -1, best_k = kNaN;
  for (double k = kmin; k <= kmax; k += dk) {
    double c = 0, sn = 0;
    for (std::size_t j = 0; j < n; ++j) {
      const double ph = k * ds * static_cast<double>(j);
      c += u[j] * std::cos(ph);
      sn += u[j] * std::sin(ph);
    }
    const double power = c * c + sn * sn;
    if (power > best) {
      best = power;
      best_k = k;
    }
  }
  return best > 0 ? 2 * std::numbers::pi / best_k : kNaN;
}

double mean_of(const std::vector<double>& v) {
  if (v.empty()) return kNaN;
  double m = 0;
  for (double x : v) m += x;
  return m / static_cast<double>(v.size());
}

double std_of(const std::vector<double>& v) {
  if (v.size() < 2) return kNaN;
  const double m = mean_of(v);
  double q = 0;
  for (double x : v) q += (x - m) * (x - m);
  return std::sqrt(q / static_cast<double>(v.size() - 1));
}

}  // namespace

int parse_axis(const std::string& name, const std::string& field) {
  if (name == "x") return 0;
  if (name == "y") return 1;
  if (name == "z") return 2;
  throw ConfigError("", field, fmt::format("\"{}\" is not an axis (x, y or z)", name));
}

double detrend_retention(double wavelength, double sigma) {
  const double k = 2 * std::numbers::pi / wavelength;
  const double x = 0.5 * k * k * sigma * sigma;
  return 1 - (1 + x) * std::exp(-x);
}

std::vector<double> local_quadratic_smooth(const std::vector<double>& t,
                                           const std::vector<double>& v, std::size_t components,
                                           double sigma) {
  const std::size_t n = t.size();
  if (v.size() != n * components) {
    throw ConfigError("", "local_quadratic_smooth", "values must have n × components entries");
  }
  std::vector<double> out(v.size());
  std::size_t lo = 0, hi = 0;
  const double reach = 4 * sigma;
  for (std::size_t j = 0; j < n; ++j) {
    while (t[lo] < t[j] - reach) ++lo;
    while (hi < n && t[hi] <= t[j] + reach) ++hi;
    // Weighted least squares of v ≈ a + b d + c d², d = (t − t_j)/σ.
    double m[5] = {0, 0, 0, 0, 0};
    std::vector<std::array<double, 3>> rhs(components, {0, 0, 0});
    for (std::size_t i = lo; i < hi; ++i) {
      const double d = (t[i] - t[j]) / sigma;
      const double w = std::exp(-0.5 * d * d);
      double p = w;
      for (double& mk : m) {
        mk += p;
        p *= d;
      }
      for (std::size_t c = 0; c < components; ++c) {
        const double val = v[i * components + c];
        rhs[c][0] += w * val;
        rhs[c][1] += w * d * val;
        rhs[c][2] += w * d * d * val;
      }
    }
    // Solve [[m0 m1 m2],[m1 m2 m3],[m2 m3 m4]] a = rhs for a[0] (Cramer's rule).
    const double det = m[0] * (m[2] * m[4] - m[3] * m[3]) - m[1] * (m[1] * m[4] - m[3] * m[2]) +
                       m[2] * (m[1] * m[3] - m[2] * m[2]);
    const bool quadratic = hi - lo >= 3 && std::abs(det) > 1e-12 * m[0] * m[0] * m[0];
    for (std::size_t c = 0; c < components; ++c) {
      const auto& b = rhs[c];
      out[j * components + c] =
          quadratic ? (b[0] * (m[2] * m[4] - m[3] * m[3]) - m[1] * (b[1] * m[4] - m[3] * b[2]) +
                       m[2] * (b[1] * m[3] - m[2] * b[2])) /
                          det
                    : b[0] / m[0];
    }
  }
  return out;
}

WrinkleReport measure_wrinkles(const SurfaceAnimation& animation, std::size_t frame,
                               const WrinkleOptions& options) {
  if (frame >= animation.frame_count()) {
    throw ConfigError(animation.file, "frame",
                      fmt::format("frame {} out of range: the surface has {} frames", frame,
                                  animation.frame_count()));
  }
  return measure_wrinkles(animation.triangles, animation.rest, animation.frames[frame], options,
                          animation.file);
}

WrinkleReport measure_wrinkles(const std::vector<std::int32_t>& triangles,
                               const std::vector<float>& rest, const std::vector<float>& deformed,
                               const WrinkleOptions& options, const std::string& file) {
  check_options(options);
  check_arrays(triangles, rest, deformed, file);
  WrinkleReport report;
  report.options = options;
  report.edge_length = median_edge(triangles, rest);
  const double sigma = options.detrend_width;
  double spacing = options.spacing;
  if (spacing == 0) spacing = std::min(report.edge_length / 4, sigma / 10);
  if (!(spacing > 0)) throw GeometryError(file, "rest", "the surface's edges have zero length");
  report.options.spacing = spacing;

  const int up = options.up, ac = options.across, al = 3 - options.up - options.across;
  const std::size_t tcount = triangles.size() / 3;

  // Candidate triangles: facing up (rest normal), non-degenerate in the (across, along) plane.
  std::vector<std::size_t> cand;
  double a0 = std::numeric_limits<double>::infinity(), a1 = -a0;
  for (std::size_t t = 0; t < tcount; ++t) {
    const auto a = vertex(rest, triangles[3 * t]), b = vertex(rest, triangles[3 * t + 1]),
               c = vertex(rest, triangles[3 * t + 2]);
    const auto f = cross(sub(b, a), sub(c, a));
    const double len = norm(f);
    if (!(len > 0) || f[up] / len < options.min_facing) continue;
    cand.push_back(t);
    for (const auto* p : {&a, &b, &c}) {
      a0 = std::min(a0, (*p)[ac]);
      a1 = std::max(a1, (*p)[ac]);
    }
  }
  if (options.region) {
    a0 = std::max(a0, (*options.region)[2 * ac]);
    a1 = std::min(a1, (*options.region)[2 * ac + 1]);
  }
  if (cand.empty() || !(a1 > a0)) {
    throw GeometryError(
        file, "triangles",
        fmt::format("no triangle faces +{} within {:.0f}° (min_facing {}){}", "xyz"[up],
                    std::acos(options.min_facing) * 180 / std::numbers::pi, options.min_facing,
                    options.region ? " inside the region" : ""));
  }
  const auto def_normals = vertex_normals(triangles, deformed);

  for (int k = 0; k < options.profiles; ++k) {
    WrinkleProfile prof;
    prof.across = a0 + (k + 1) * (a1 - a0) / (options.profiles + 1);
    const double c = prof.across;
    // Triangles crossed by the line across = c, and their along intervals.
    struct Span {
      std::size_t t;
      double b0, b1;
    };
    std::vector<Span> spans;
    double bmin = std::numeric_limits<double>::infinity(), bmax = -bmin;
    for (auto t : cand) {
      std::array<V3, 3> p;
      for (int q = 0; q < 3; ++q) p[q] = vertex(rest, triangles[3 * t + q]);
      double lo = std::numeric_limits<double>::infinity(), hi = -lo;
      for (int q = 0; q < 3; ++q) {
        const auto& e0 = p[q];
        const auto& e1 = p[(q + 1) % 3];
        const double d0 = e0[ac] - c, d1 = e1[ac] - c;
        if ((d0 < 0 && d1 < 0) || (d0 > 0 && d1 > 0)) continue;
        if (d0 == d1) {  // the edge lies on the line
          lo = std::min({lo, e0[al], e1[al]});
          hi = std::max({hi, e0[al], e1[al]});
          continue;
        }
        const double w = d0 / (d0 - d1);
        const double b = e0[al] + w * (e1[al] - e0[al]);
        lo = std::min(lo, b);
        hi = std::max(hi, b);
      }
      if (lo > hi) continue;
      spans.push_back({t, lo, hi});
      bmin = std::min(bmin, lo);
      bmax = std::max(bmax, hi);
    }
    if (spans.empty()) {
      report.profiles.push_back(prof);
      continue;
    }
    const auto npts = static_cast<std::size_t>(std::floor((bmax - bmin) / spacing)) + 1;
    std::vector<Hit> hits(npts);
    for (const auto& sp : spans) {
      std::array<V3, 3> p;
      for (int q = 0; q < 3; ++q) p[q] = vertex(rest, triangles[3 * sp.t + q]);
      // 2-D barycentric coordinates in the (across, along) plane.
      const double x0 = p[0][ac], y0 = p[0][al], x1 = p[1][ac], y1 = p[1][al], x2 = p[2][ac],
                   y2 = p[2][al];
      const double det = (y1 - y2) * (x0 - x2) + (x2 - x1) * (y0 - y2);
      if (det == 0) continue;
      const auto j0 = static_cast<std::size_t>(std::max(0.0, std::ceil((sp.b0 - bmin) / spacing)));
      for (std::size_t j = j0; j < npts; ++j) {
        const double b = bmin + spacing * static_cast<double>(j);
        if (b > sp.b1) break;
        double l0 = ((y1 - y2) * (c - x2) + (x2 - x1) * (b - y2)) / det;
        double l1 = ((y2 - y0) * (c - x2) + (x0 - x2) * (b - y2)) / det;
        double l2 = 1 - l0 - l1;
        const double tol = -1e-9;
        if (l0 < tol || l1 < tol || l2 < tol) continue;
        l0 = std::max(l0, 0.0);
        l1 = std::max(l1, 0.0);
        l2 = std::max(l2, 0.0);
        const double sum = l0 + l1 + l2;
        const V3 bary{l0 / sum, l1 / sum, l2 / sum};
        const double height = bary[0] * p[0][up] + bary[1] * p[1][up] + bary[2] * p[2][up];
        if (height > hits[j].height) hits[j] = {true, height, sp.t, bary};
      }
    }
    // Rest and deformed positions, deformed normals; the region.
    std::vector<V3> X(npts), x(npts), nd(npts);
    for (std::size_t j = 0; j < npts; ++j) {
      if (!hits[j].valid) continue;
      V3 Xj{0, 0, 0}, xj{0, 0, 0}, nj{0, 0, 0};
      for (int q = 0; q < 3; ++q) {
        const auto v = triangles[3 * hits[j].triangle + q];
        const auto Xv = vertex(rest, v), xv = vertex(deformed, v);
        const auto& nv = def_normals[static_cast<std::size_t>(v)];
        const double nl = norm(nv);
        for (int i = 0; i < 3; ++i) {
          Xj[i] += hits[j].bary[q] * Xv[i];
          xj[i] += hits[j].bary[q] * xv[i];
          if (nl > 0) nj[i] += hits[j].bary[q] * nv[i] / nl;
        }
      }
      X[j] = Xj;
      x[j] = xj;
      nd[j] = nj;
      if (options.region) {
        const auto& r = *options.region;
        for (int i = 0; i < 3; ++i) {
          if (Xj[i] < r[2 * i] || Xj[i] > r[2 * i + 1]) hits[j].valid = false;
        }
      }
    }
    // The longest run of consecutive valid samples.
    std::size_t best0 = 0, best_len = 0;
    for (std::size_t j = 0; j < npts;) {
      if (!hits[j].valid) {
        ++j;
        continue;
      }
      std::size_t e = j;
      while (e < npts && hits[e].valid) ++e;
      if (e - j > best_len) {
        best0 = j;
        best_len = e - j;
      }
      j = e;
    }
    if (best_len < kMinSamples) {
      log::debug("wrinkles: profile {} at {} = {:.4g} m has {} samples: skipped", k, "xyz"[ac], c,
                 best_len);
      report.profiles.push_back(prof);
      continue;
    }
    const std::size_t n = best_len;
    std::vector<double> v(n), s(n), uv(3 * n), Xv(3 * n), nv(3 * n);
    for (std::size_t j = 0; j < n; ++j) {
      const auto& Xj = X[best0 + j];
      const auto& xj = x[best0 + j];
      const auto& nj = nd[best0 + j];
      v[j] = spacing * static_cast<double>(j);
      for (int i = 0; i < 3; ++i) {
        uv[3 * j + i] = xj[i] - Xj[i];
        Xv[3 * j + i] = Xj[i];
        nv[3 * j + i] = nj[i];
      }
    }
    // The arc length of the smoothed rest curve, not of the raw polyline: on a voxel staircase
    // (the volume's boundary) the raw one would count every riser.
    const auto X0 = local_quadratic_smooth(v, Xv, 3, sigma);
    for (std::size_t j = 1; j < n; ++j) {
      const V3 d{X0[3 * j] - X0[3 * j - 3], X0[3 * j + 1] - X0[3 * j - 2],
                 X0[3 * j + 2] - X0[3 * j - 1]};
      s[j] = s[j - 1] + std::max(norm(d), 1e-9 * spacing);
    }
    const auto ub = local_quadratic_smooth(s, uv, 3, sigma);
    const auto Xb = local_quadratic_smooth(s, Xv, 3, sigma);
    const auto nb = local_quadratic_smooth(s, nv, 3, sigma);
    prof.samples = n;
    prof.s = s;
    prof.arc.assign(n, 0.0);
    prof.residual.assign(n, 0.0);
    prof.local_strain.assign(n, 0.0);
    prof.rest = Xv;
    double sq = 0;
    prof.strain_min = std::numeric_limits<double>::infinity();
    for (std::size_t j = 0; j < n; ++j) {
      V3 nbar{nb[3 * j], nb[3 * j + 1], nb[3 * j + 2]};
      const double nl = norm(nbar);
      if (nl > 0) {
        for (double& q : nbar) q /= nl;
      }
      if (nbar[up] < 0) {
        for (double& q : nbar) q = -q;
      }
      const V3 du{uv[3 * j] - ub[3 * j], uv[3 * j + 1] - ub[3 * j + 1],
                  uv[3 * j + 2] - ub[3 * j + 2]};
      prof.residual[j] = dot(du, nbar);
      sq += prof.residual[j] * prof.residual[j];
      if (j > 0) {
        V3 dX, dx;
        for (int i = 0; i < 3; ++i) {
          dX[i] = Xb[3 * j + i] - Xb[3 * (j - 1) + i];
          dx[i] = dX[i] + ub[3 * j + i] - ub[3 * (j - 1) + i];
        }
        const double l0 = norm(dX), l = norm(dx);
        prof.length_rest += l0;
        prof.length += l;
        prof.arc[j] = prof.arc[j - 1] + l;
        prof.local_strain[j] = l0 > 0 ? l / l0 - 1 : 0;
        prof.strain_min = std::min(prof.strain_min, prof.local_strain[j]);
      }
    }
    prof.local_strain[0] = prof.local_strain[1];
    prof.rms = std::sqrt(sq / static_cast<double>(n));
    prof.strain = prof.length_rest > 0 ? prof.length / prof.length_rest - 1 : 0;

    find_folds(prof, options.min_depth, up);
    for (auto& f : prof.folds) {
      // The trough's index: folds store s, which is one of the samples.
      const auto it = std::lower_bound(s.begin(), s.end(), f.s);
      const auto t = static_cast<std::size_t>(it - s.begin());
      const std::size_t a = t > 0 ? t - 1 : t, b = t + 1 < n ? t + 1 : t;
      const double slope = b > a ? std::abs(Xb[3 * b + static_cast<std::size_t>(up)] -
                                            Xb[3 * a + static_cast<std::size_t>(up)]) /
                                       (s[b] - s[a])
                                 : 0;
      f.layer_period =
          options.voxel_size > 0
              ? (slope > 0 ? options.voxel_size / slope : std::numeric_limits<double>::infinity())
              : kNaN;
    }
    std::vector<double> gaps, depths;
    for (std::size_t f = 0; f < prof.folds.size(); ++f) {
      depths.push_back(prof.folds[f].depth);
      if (f > 0) gaps.push_back(prof.folds[f].arc - prof.folds[f - 1].arc);
    }
    prof.wavelength_mean = mean_of(gaps);
    prof.wavelength_std = std_of(gaps);
    prof.depth_mean = mean_of(depths);
    prof.depth_max = depths.empty() ? 0 : *std::max_element(depths.begin(), depths.end());
    const double lmin = std::max(4 * spacing, 2 * report.edge_length);
    const double lspec = prof.rms > 0 ? spectral_peak(s, prof.residual, lmin, s.back() / 2) : kNaN;
    prof.spectral_wavelength = lspec * (1 + prof.strain);
    report.profiles.push_back(std::move(prof));
  }

  auto& sum = report.summary;
  std::vector<double> gaps, depths, spectral;
  double sq = 0, strain = 0;
  std::size_t samples = 0;
  sum.strain_min = std::numeric_limits<double>::infinity();
  for (const auto& p : report.profiles) {
    if (p.samples == 0) continue;
    ++sum.profiles_used;
    sum.folds += p.folds.size();
    for (std::size_t f = 0; f < p.folds.size(); ++f) {
      depths.push_back(p.folds[f].depth);
      if (f > 0) gaps.push_back(p.folds[f].arc - p.folds[f - 1].arc);
    }
    if (std::isfinite(p.spectral_wavelength)) spectral.push_back(p.spectral_wavelength);
    sq += p.rms * p.rms * static_cast<double>(p.samples);
    samples += p.samples;
    strain += p.strain;
    sum.strain_min = std::min(sum.strain_min, p.strain_min);
  }
  // Phases of the troughs within the voxel layers.
  double cs = 0, sn = 0, hmin = std::numeric_limits<double>::infinity(), hmax = -hmin;
  std::size_t nf = 0;
  for (auto& p : report.profiles) {
    for (auto& f : p.folds) {
      if (options.voxel_size > 0) {
        const double q =
            (f.height - options.lattice_origin[static_cast<std::size_t>(up)]) / options.voxel_size;
        f.layer_phase = q - std::floor(q);
        cs += std::cos(2 * std::numbers::pi * f.layer_phase);
        sn += std::sin(2 * std::numbers::pi * f.layer_phase);
        hmin = std::min(hmin, f.height);
        hmax = std::max(hmax, f.height);
        ++nf;
      } else {
        f.layer_phase = kNaN;
      }
    }
  }
  sum.layer_locking = nf > 0 ? std::hypot(cs, sn) / static_cast<double>(nf) : kNaN;
  std::vector<double> periods;
  for (const auto& p : report.profiles) {
    for (const auto& f : p.folds) {
      if (options.voxel_size > 0) periods.push_back(f.layer_period);
    }
  }
  sum.layer_period = upper_median(std::move(periods));
  sum.layers_spanned = nf > 0 ? (hmax - hmin) / options.voxel_size : kNaN;
  if (sum.profiles_used == 0) {
    throw GeometryError(file, "triangles",
                        fmt::format("none of the {} profiles (lines {} = const) meets {} samples "
                                    "of the surface facing +{}{}",
                                    options.profiles, "xyz"[ac], kMinSamples, "xyz"[up],
                                    options.region ? " inside the region" : ""));
  }
  const auto used = static_cast<double>(sum.profiles_used);
  sum.folds_mean = static_cast<double>(sum.folds) / used;
  sum.wavelength_mean = mean_of(gaps);
  sum.wavelength_std = std_of(gaps);
  sum.wavelength_count = gaps.size();
  sum.spectral_wavelength = upper_median(std::move(spectral));
  sum.depth_mean = mean_of(depths);
  sum.depth_max = depths.empty() ? 0 : *std::max_element(depths.begin(), depths.end());
  sum.rms = std::sqrt(sq / static_cast<double>(samples));
  sum.strain = strain / used;
  const double lw =
      std::isfinite(sum.wavelength_mean) ? sum.wavelength_mean : sum.spectral_wavelength;
  // The fit works in rest arc length: a deformed wavelength λ was λ / (1 + strain) at rest.
  sum.retention = std::isfinite(lw) ? detrend_retention(lw / (1 + sum.strain), sigma) : kNaN;
  return report;
}

}  // namespace sinew::postprocess
