#include "sinew/simulator/passes/sliding_grid.hpp"

#include <algorithm>
#include <cmath>

namespace sinew::simulator {

SurfaceGrid build_surface_grid(const std::vector<std::array<double, 3>>& vertices,
                               const std::vector<std::array<std::int32_t, 3>>& triangles) {
  SurfaceGrid g;
  std::array<double, 3> lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (const auto& v : vertices)
    for (int k = 0; k < 3; ++k) {
      lo[std::size_t(k)] = std::min(lo[std::size_t(k)], v[std::size_t(k)]);
      hi[std::size_t(k)] = std::max(hi[std::size_t(k)], v[std::size_t(k)]);
    }
  double edge = 0;
  for (const auto& t : triangles)
    for (int a = 0; a < 3; ++a) {
      const auto& p = vertices[std::size_t(t[std::size_t(a)])];
      const auto& q = vertices[std::size_t(t[std::size_t((a + 1) % 3)])];
      edge += std::hypot(p[0] - q[0], p[1] - q[1], p[2] - q[2]);
    }
  edge /= std::max<std::size_t>(1, 3 * triangles.size());
  const double ext = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], 1e-12});
  double vol = 1;
  for (int k = 0; k < 3; ++k) vol *= std::max(hi[std::size_t(k)] - lo[std::size_t(k)], 1e-3 * ext);
  // Surfaces are 2-D: cells about one mean edge wide hold a few triangles each (with the query's
  // box culls, ~12 box tests and ~3 exact tests per node one edge off the face-scale skull, against
  // ~18 and 3 with cells 1.5 edges wide); the volume bound keeps the cell count within 64 per
  // triangle for very flat or sparse surfaces.
  const double volume_cell =
      std::cbrt(vol / (64.0 * double(std::max<std::size_t>(1, triangles.size()))));
  const double cell = std::max({edge, volume_cell, 1e-6 * ext});
  g.cell = cell;
  for (int k = 0; k < 3; ++k) {
    g.origin[std::size_t(k)] = lo[std::size_t(k)];
    g.dims[std::size_t(k)] = std::max<std::int32_t>(
        1, std::int32_t(std::ceil((hi[std::size_t(k)] - lo[std::size_t(k)]) / cell)));
    // guarantee coverage of hi
    while (g.origin[std::size_t(k)] + g.dims[std::size_t(k)] * cell < hi[std::size_t(k)])
      ++g.dims[std::size_t(k)];
  }
  const std::size_t cells =
      std::size_t(g.dims[0]) * std::size_t(g.dims[1]) * std::size_t(g.dims[2]);
  auto cell_range = [&](std::size_t t, std::array<std::int32_t, 3>& a,
                        std::array<std::int32_t, 3>& b) {
    for (int k = 0; k < 3; ++k) {
      double mn = 1e300, mx = -1e300;
      for (int c = 0; c < 3; ++c) {
        const double v = vertices[std::size_t(triangles[t][std::size_t(c)])][std::size_t(k)];
        mn = std::min(mn, v);
        mx = std::max(mx, v);
      }
      const auto ks = std::size_t(k);
      a[ks] = std::clamp(std::int32_t(std::floor((mn - g.origin[ks]) / cell)), 0, g.dims[ks] - 1);
      b[ks] = std::clamp(std::int32_t(std::floor((mx - g.origin[ks]) / cell)), 0, g.dims[ks] - 1);
    }
  };
  std::vector<std::int32_t> counts(cells + 1, 0);
  std::array<std::int32_t, 3> a{}, b{};
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    cell_range(t, a, b);
    for (auto k = a[2]; k <= b[2]; ++k)
      for (auto j = a[1]; j <= b[1]; ++j)
        for (auto i = a[0]; i <= b[0]; ++i)
          ++counts[std::size_t((k * g.dims[1] + j) * g.dims[0] + i) + 1];
  }
  for (std::size_t c = 0; c < cells; ++c) counts[c + 1] += counts[c];
  g.cell_offsets = counts;
  g.cell_triangles.resize(std::size_t(counts[cells]));
  std::vector<std::int32_t> fill(counts.begin(), counts.end() - 1);
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    cell_range(t, a, b);
    for (auto k = a[2]; k <= b[2]; ++k)
      for (auto j = a[1]; j <= b[1]; ++j)
        for (auto i = a[0]; i <= b[0]; ++i)
          g.cell_triangles[std::size_t(fill[std::size_t((k * g.dims[1] + j) * g.dims[0] + i)]++)] =
              std::int32_t(t);
  }
  return g;
}

}  // namespace sinew::simulator
