#include "sinew/voxelizer/fibres.hpp"

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/Sparse>
#include <algorithm>
#include <cmath>
#include <string>

#include "sinew/common/error.hpp"

namespace sinew::voxelizer {

using formats::lattice_less;

HarmonicFibres harmonic_fibres(const std::vector<formats::Lattice>& voxels,
                               const std::vector<DirichletTag>& tags, const std::string& name,
                               const std::vector<double>& fractions) {
  auto weight = [&](std::size_t v) { return fractions.empty() ? 1.0 : fractions[v]; };
  const std::size_t n = voxels.size();
  HarmonicFibres out;
  Vec3d origin_c{0, 0, 0}, insertion_c{0, 0, 0};
  std::int64_t n_origin = 0, n_insertion = 0;
  for (std::size_t v = 0; v < n; ++v) {
    const Vec3d p{double(voxels[v][0]), double(voxels[v][1]), double(voxels[v][2])};
    if (tags[v] == DirichletTag::origin) origin_c += p, ++n_origin;
    if (tags[v] == DirichletTag::insertion) insertion_c += p, ++n_insertion;
  }
  if (n_origin == 0) {
    throw GeometryError("", name, "no voxel of the muscle lies in its fibre origin region");
  }
  if (n_insertion == 0) {
    throw GeometryError("", name, "no voxel of the muscle lies in its fibre insertion region");
  }
  Vec3d axis = (1.0 / n_insertion) * insertion_c - (1.0 / n_origin) * origin_c;
  axis = norm(axis) > 0 ? (1.0 / norm(axis)) * axis : Vec3d{1, 0, 0};

  // Neighbour lookup on the sorted lattice.
  auto find = [&](const formats::Lattice& q) -> std::int64_t {
    const auto it = std::lower_bound(voxels.begin(), voxels.end(), q, lattice_less);
    return (it != voxels.end() && *it == q) ? it - voxels.begin() : -1;
  };
  std::vector<std::array<std::int64_t, 6>> nb(n);
  for (std::size_t v = 0; v < n; ++v) {
    for (int d = 0; d < 3; ++d) {
      for (int s = 0; s < 2; ++s) {
        formats::Lattice q = voxels[v];
        q[static_cast<std::size_t>(d)] += s ? 1 : -1;
        nb[v][static_cast<std::size_t>(2 * d + s)] = find(q);
      }
    }
  }
  // Unknowns: the free voxels.
  std::vector<std::int64_t> unknown(n, -1);
  std::int64_t m = 0;
  for (std::size_t v = 0; v < n; ++v)
    if (tags[v] == DirichletTag::free) unknown[v] = m++;
  std::vector<double> u(n, 0.0);
  for (std::size_t v = 0; v < n; ++v) u[v] = tags[v] == DirichletTag::insertion ? 1.0 : 0.0;
  if (m > 0) {
    std::vector<Eigen::Triplet<double>> trip;
    trip.reserve(static_cast<std::size_t>(m) * 7);
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(m);
    for (std::size_t v = 0; v < n; ++v) {
      const auto row = unknown[v];
      if (row < 0) continue;
      double diag = 0;
      for (auto w : nb[v]) {
        if (w < 0) continue;
        const double c = 0.5 * (weight(v) + weight(static_cast<std::size_t>(w)));
        diag += c;
        const auto col = unknown[static_cast<std::size_t>(w)];
        if (col >= 0) {
          trip.emplace_back(row, col, -c);
        } else {
          rhs[row] += c * u[static_cast<std::size_t>(w)];
        }
      }
      // An isolated free voxel keeps u = 0 (a 1 on the diagonal keeps the matrix regular).
      trip.emplace_back(row, row, diag > 0 ? diag : 1.0);
    }
    // Column-major with the full matrix: Eigen's CG then runs single-threaded, so the result is
    // independent of the thread count.
    Eigen::SparseMatrix<double> a(m, m);
    a.setFromTriplets(trip.begin(), trip.end());
    Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper> cg;
    cg.setTolerance(1e-10);
    cg.setMaxIterations(static_cast<Eigen::Index>(std::max<std::int64_t>(1000, 20 * m)));
    cg.compute(a);
    const Eigen::VectorXd x = cg.solve(rhs);
    out.iterations = static_cast<int>(cg.iterations());
    out.residual = cg.error();
    for (std::size_t v = 0; v < n; ++v)
      if (unknown[v] >= 0) u[v] = x[unknown[v]];
  }
  out.potential = u;
  out.fibres.resize(n);
  std::vector<char> has(n, 0);
  for (std::size_t v = 0; v < n; ++v) {
    Vec3d g{0, 0, 0};
    for (int d = 0; d < 3; ++d) {
      const auto lo = nb[v][static_cast<std::size_t>(2 * d)];
      const auto hi = nb[v][static_cast<std::size_t>(2 * d + 1)];
      double val = 0;
      if (lo >= 0 && hi >= 0) {
        val = 0.5 * (u[static_cast<std::size_t>(hi)] - u[static_cast<std::size_t>(lo)]);
      } else if (hi >= 0) {
        val = u[static_cast<std::size_t>(hi)] - u[v];
      } else if (lo >= 0) {
        val = u[v] - u[static_cast<std::size_t>(lo)];
      }
      g[d] = val;
    }
    const double len = norm(g);
    if (len > 1e-12) {
      out.fibres[v] = (1.0 / len) * g;
      has[v] = 1;
    }
  }
  // Inside an origin or insertion region u is constant: extend the fibres from the neighbours,
  // one lattice layer per pass (each pass reads the previous one, so the order does not matter).
  for (bool changed = true; changed;) {
    changed = false;
    std::vector<char> next = has;
    std::vector<Vec3d> fib = out.fibres;
    for (std::size_t v = 0; v < n; ++v) {
      if (has[v]) continue;
      Vec3d sum{0, 0, 0};
      for (auto w : nb[v])
        if (w >= 0 && has[static_cast<std::size_t>(w)])
          sum += out.fibres[static_cast<std::size_t>(w)];
      const double len = norm(sum);
      if (len > 1e-12) {
        fib[v] = (1.0 / len) * sum;
        next[v] = 1;
        changed = true;
      }
    }
    has = std::move(next);
    out.fibres = std::move(fib);
  }
  for (std::size_t v = 0; v < n; ++v) {
    if (!has[v]) {
      out.fibres[v] = axis;
      ++out.fallback;
    }
  }
  return out;
}

Vec3d circumferential_fibre(const Vec3d& p, const Vec3d& centre, const Vec3d& axis,
                            const Vec3d& major, double radius_major, double radius_minor) {
  const Vec3d minor = cross(axis, major);
  const Vec3d x = p - centre;
  const Vec3d grad = (dot(x, major) / (radius_major * radius_major)) * major +
                     (dot(x, minor) / (radius_minor * radius_minor)) * minor;
  const Vec3d t = cross(axis, grad);
  const double len = norm(t);
  return len > 1e-300 ? (1.0 / len) * t : minor;
}

}  // namespace sinew::voxelizer
