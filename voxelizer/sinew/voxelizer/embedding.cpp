#include "sinew/voxelizer/embedding.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sinew/common/error.hpp"

namespace sinew::voxelizer {

using formats::lattice_less;

Embedding embed_points(const formats::Model& model, const std::vector<formats::Point>& points) {
  const auto& g = model.grid;
  const double h = g.voxel_size;
  const auto& elements = model.element_lattice;
  auto find = [&](const formats::Lattice& q) -> formats::Index {
    if (q[0] < 0 || q[1] < 0 || q[2] < 0 || q[0] >= g.dims[0] || q[1] >= g.dims[1] ||
        q[2] >= g.dims[2]) {
      return -1;
    }
    const auto it = std::lower_bound(elements.begin(), elements.end(), q, lattice_less);
    return (it != elements.end() && *it == q) ? static_cast<formats::Index>(it - elements.begin())
                                              : -1;
  };
  Embedding out;
  const std::size_t np = points.size();
  out.element.assign(np, -1);
  out.local.assign(np, {0, 0, 0});
  std::vector<double> outside_distance(np, -1.0);
  if (elements.empty()) {
    throw GeometryError("", "embedding", "the model has no elements to bind a surface to");
  }
#pragma omp parallel for schedule(dynamic, 256)
  for (std::int64_t q = 0; q < static_cast<std::int64_t>(np); ++q) {
    const auto& p = points[static_cast<std::size_t>(q)];
    double t[3];
    int base[3];
    for (int d = 0; d < 3; ++d) {
      t[d] = (p[static_cast<std::size_t>(d)] - g.origin[static_cast<std::size_t>(d)]) / h;
      base[d] = static_cast<int>(std::floor(t[d]));
    }
    // Candidate cells containing p (more than one when p is on a shared face, edge or corner).
    formats::Index found = -1;
    formats::Lattice cell{};
    for (int dz = 0; dz < 2 && found < 0; ++dz) {
      for (int dy = 0; dy < 2 && found < 0; ++dy) {
        for (int dx = 0; dx < 2 && found < 0; ++dx) {
          const int off[3] = {dx, dy, dz};
          formats::Lattice c{};
          bool ok = true;
          for (int d = 0; d < 3; ++d) {
            const double frac = t[d] - base[d];
            if (off[d] == 0) {
              c[static_cast<std::size_t>(d)] = base[d];
            } else if (frac < 1e-9) {
              c[static_cast<std::size_t>(d)] = base[d] - 1;
            } else if (frac > 1 - 1e-9) {
              c[static_cast<std::size_t>(d)] = base[d] + 1;
            } else {
              ok = false;
            }
          }
          if (!ok) continue;
          found = find(c);
          cell = c;
        }
      }
    }
    if (found < 0) {
      // Nearest present element by the distance to its box: search lattice shells outward.
      double best = std::numeric_limits<double>::infinity();
      int max_r = 1;
      for (int d = 0; d < 3; ++d) {
        max_r = std::max({max_r, std::abs(base[d]) + 1, std::abs(base[d] - g.dims[d]) + 1});
      }
      int stop = max_r;
      for (int r = 0; r <= std::min(stop, max_r); ++r) {
        // The shell of Chebyshev radius r around the base cell: full planes at k = ±r, full rows
        // at j = ±r, the two end cells i = ±r elsewhere.
        for (int k = base[2] - r; k <= base[2] + r; ++k) {
          const bool k_face = std::abs(k - base[2]) == r;
          for (int j = base[1] - r; j <= base[1] + r; ++j) {
            const bool j_face = std::abs(j - base[1]) == r;
            const int step = (k_face || j_face || r == 0) ? 1 : 2 * r;
            for (int i = base[0] - r; i <= base[0] + r; i += step) {
              const formats::Lattice c{i, j, k};
              const auto e = find(c);
              if (e < 0) continue;
              double d2 = 0;
              for (int d = 0; d < 3; ++d) {
                const double lo = c[static_cast<std::size_t>(d)], hi = lo + 1;
                const double x = std::clamp(t[d], lo, hi);
                d2 += (t[d] - x) * (t[d] - x);
              }
              if (d2 < best || (d2 == best && lattice_less(c, cell))) {
                best = d2;
                found = e;
                cell = c;
              }
            }
          }
        }
        // Once something is found at shell r, nothing beyond shell r·√3 + 1 can be nearer.
        if (found >= 0 && stop == max_r)
          stop = static_cast<int>(std::ceil(r * 1.7320508075688772)) + 1;
      }
      outside_distance[static_cast<std::size_t>(q)] = std::sqrt(best) * h;
    }
    out.element[static_cast<std::size_t>(q)] = found;
    formats::Point xi{};
    for (int d = 0; d < 3; ++d) {
      const double v = 2.0 * (t[d] - cell[static_cast<std::size_t>(d)]) - 1.0;
      xi[static_cast<std::size_t>(d)] = std::clamp(v, -1.0, 1.0);
    }
    out.local[static_cast<std::size_t>(q)] = xi;
  }
  for (double d : outside_distance) {
    if (d >= 0) {
      ++out.outside;
      out.max_outside_distance = std::max(out.max_outside_distance, d);
    }
  }
  return out;
}

formats::Point embedded_position(const formats::Model& model, formats::Index element,
                                 const formats::Point& local) {
  formats::Point x{0, 0, 0};
  const auto& nodes = model.element_nodes[static_cast<std::size_t>(element)];
  for (std::size_t a = 0; a < 8; ++a) {
    double n = 0.125;
    for (std::size_t d = 0; d < 3; ++d) {
      const double sign = 2.0 * formats::kHexCorner[a][d] - 1.0;
      n *= 1.0 + sign * local[d];
    }
    const auto xa = model.node_position(nodes[a]);
    for (std::size_t d = 0; d < 3; ++d) x[d] += n * xa[d];
  }
  return x;
}

}  // namespace sinew::voxelizer
