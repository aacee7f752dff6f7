#pragma once
// Generalized winding number of a triangle mesh (Jacobson, Kavan, Sorkine-Hornung 2013,
// "Robust inside-outside segmentation using generalized winding numbers"):
//
//   w(q) = 1/(4 pi) * sum_t Omega_t(q),
//   tan(Omega_t / 2) = det[a b c] / (|a||b||c| + (a.b)|c| + (b.c)|a| + (c.a)|b|),
//   a, b, c = triangle corners minus q (Van Oosterom & Strackee 1983),
//
// evaluated hierarchically as in Barill, Dickson, Schmidt, Levin, Jacobson 2018 ("Fast winding
// numbers for soups and clouds"): a bounding volume hierarchy over the triangles; a node whose
// expansion centre p (area-weighted centroid) is farther from q than accuracy_beta times its
// radius (farthest corner from p) contributes its Taylor expansion of
//   sum_t int_t grad G(x - q) . n dA,  G(r) = -1/(4 pi |r|),
// to second order (dipole, first and second moments of the triangles about p); nearer nodes are
// opened and leaves are summed exactly.
//
// w is 1 inside and 0 outside a closed outward-oriented mesh, 1/2 on its surface, and varies
// smoothly across holes, so inside = w >= 1/2 is robust to holes, non-manifold edges, several
// components and triangle soups. Units: any (w is dimensionless); q in the mesh's coordinates.
//
// Accuracy of the hierarchical value against the exact sum (max |difference| on random points in
// and around the mesh, measured): beta = 2: 5.5e-3 (bumpy sphere and torus, tests) and 6.2e-3
// (Armadillo, 100k triangles; mean 8.9e-4); beta = 3: 1.0e-3; beta = 4: 2.7e-4 (tests) and
// 2.5e-4 (Armadillo). The far field's error shrinks like beta^-3, its cost grows about like
// beta^2. Classification (inside(), classify()) does not depend on it: values within 0.02 of 1/2
// are recomputed at beta = max(4, accuracy_beta).
#include <cstdint>
#include <memory>
#include <vector>

#include "sinew/common/math.hpp"
#include "sinew/voxelizer/mesh.hpp"

namespace sinew::voxelizer {

// Signed solid angle (steradians, in (-2 pi, 2 pi)) of triangle (a, b, c) seen from q; positive
// when q is on the side opposite the normal (b - a) x (c - a) points to. 0 when q lies in its
// plane, on the triangle included (so w = 1/2 exactly on the faces of a closed mesh).
double triangle_solid_angle(const sinew::Vec3d& a, const sinew::Vec3d& b, const sinew::Vec3d& c,
                            const sinew::Vec3d& q);

class WindingNumber {
 public:
  // Copies what it needs from mesh (the mesh may be destroyed afterwards). accuracy_beta > 1:
  // larger is more accurate and slower (Barill et al. use 2). Throws GeometryError if the mesh has
  // no triangles or beta <= 1.
  explicit WindingNumber(const TriangleMesh& mesh, double accuracy_beta = 2.0);
  ~WindingNumber();
  WindingNumber(WindingNumber&&) noexcept;
  WindingNumber& operator=(WindingNumber&&) noexcept;
  WindingNumber(const WindingNumber&) = delete;
  WindingNumber& operator=(const WindingNumber&) = delete;

  // Hierarchical w(p). Thread-safe (const, no shared mutable state).
  double operator()(const sinew::Vec3d& p) const;
  // w(p) >= 0.5, recomputed at beta >= 4 when the hierarchical w is within 0.02 of 0.5.
  bool inside(const sinew::Vec3d& p) const;
  // out[i] = inside(points[i]) ? 1 : 0 (out is resized); OpenMP, thread-count independent.
  void classify(const std::vector<sinew::Vec3d>& points, std::vector<std::uint8_t>& out) const;
  // out[i] = w(points[i]) for all i (out is resized). OpenMP-parallel; each value is computed by
  // one thread in a fixed order, so the result does not depend on the thread count.
  void evaluate(const std::vector<sinew::Vec3d>& points, std::vector<double>& out) const;
  // Brute force: the exact sum over all triangles (O(n_triangles)); for tests and references.
  double exact(const sinew::Vec3d& p) const;

  double accuracy_beta() const;
  std::int64_t triangle_count() const;
  std::int64_t node_count() const;  // BVH nodes

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sinew::voxelizer
