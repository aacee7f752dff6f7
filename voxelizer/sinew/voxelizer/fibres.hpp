#pragma once
// Muscle fibre fields (reference configuration), one unit vector per element of a muscle.
//
// Harmonic fibres (Choi & Blemker 2013, "Skeletal muscle fascicle arrangements can be
// reconstructed using a Laplacian vector field simulation"): solve Laplace's equation ∇²u = 0 on
// the muscle's voxels with u = 0 on the origin voxels and u = 1 on the insertion voxels, zero flux
// elsewhere (the muscle's boundary); the fibre direction is ∇u / |∇u|.
// Discretisation: the 7-point graph Laplacian on the voxel lattice (neighbours that are muscle
// voxels), each face weighted by the mean of its two voxels' muscle fractions so that partly
// filled boundary voxels conduct less (a staircase then approximates a tilted boundary), solved
// with Eigen's conjugate gradient (diagonal preconditioner, relative residual 1e-10); ∇u by central
// differences, one-sided where a neighbour is missing.
#include <cstdint>
#include <vector>

#include "sinew/common/math.hpp"
#include "sinew/formats/model.hpp"

namespace sinew::voxelizer {

enum class DirichletTag : std::int8_t { free = 0, origin = 1, insertion = 2 };

struct HarmonicFibres {
  std::vector<Vec3d> fibres;      // one unit vector per voxel, same order as the input
  std::vector<double> potential;  // u per voxel, in [0, 1]
  // Voxels where |∇u| vanishes (inside an origin or insertion region) take the mean fibre of their
  // neighbours, layer by layer; those still without one (a component with no gradient at all)
  // get the origin→insertion axis and are counted here.
  std::int64_t fallback = 0;
  int iterations = 0;
  double residual = 0;  // relative residual reached
};

// voxels: lattice coordinates of the muscle's voxels, sorted (k, j, i), unique. tags: one per
// voxel. fractions: the muscle's volume fraction per voxel in (0, 1] (empty = all 1). Throws
// GeometryError (field = `name`) when no voxel is tagged origin or insertion.
HarmonicFibres harmonic_fibres(const std::vector<formats::Lattice>& voxels,
                               const std::vector<DirichletTag>& tags, const std::string& name,
                               const std::vector<double>& fractions = {});

// Circumferential fibres for sphincters (orbicularis oculi and oris), which a harmonic
// origin→insertion field cannot give: around the axis a (unit) through the centre c, tangent to the
// family of similar ellipses q(x) = (x·M)²/A² + (x·N)²/B² = const in the plane normal to a, with
// x = p − c, M the unit major axis, N = a × M, A and B the semi-axes (only A/B matters):
//   f(p) = a × ∇q / |a × ∇q|,  ∇q = 2 ((x·M)/A² M + (x·N)/B² N).
// On the axis (∇q = 0) f = N, the tangent at the major axis' ends. Units: any (c, p alike).
Vec3d circumferential_fibre(const Vec3d& p, const Vec3d& centre, const Vec3d& axis,
                            const Vec3d& major, double radius_major, double radius_minor);

}  // namespace sinew::voxelizer
