#pragma once
// Per-voxel material volume fractions (paper §3, §4, §6.4; physics-notes §2 "non-conforming
// elements").
//
// Every point x of space gets one label:
//   0 (no tissue)          outside the outer surface (skin), or inside the inner surface (skull);
//   a body's label         inside a body (region, muscle, tendon): the body of highest precedence;
//   1 + i (layer i)        otherwise, by depth below the skin: b_{i-1} <= depth(x) < b_i.
// Inside/outside of a mesh is the generalized winding number w >= 1/2 (Jacobson et al. 2013, fast
// evaluation Barill et al. 2018); depth is the exact unsigned distance to the skin (CGAL AABB
// tree).
//
// A voxel's fraction of label L is vol{x in voxel : label(x) = L} / h³, integrated adaptively:
// a cell (block of voxels, voxel or sub-cell) of half-diagonal r whose centre values satisfy
// |s(c) - t| >= r for every field s and each of its thresholds t is uniform, because every field
// is a signed distance and hence 1-Lipschitz (s(x) = +dist inside, -dist outside). A crossed
// voxel is split into 8 children up to `max_subdivision` levels. In a crossed leaf the field is
// linearised at the leaf centre, s(x) ≈ s(c) + ∇s(c)·(x - c), ∇s = ±(c -
// closest)/dist, and the volume of the leaf on each side of each threshold plane is integrated
// exactly (cube_fraction_below). So a layer thinner than the voxel (stratum corneum, 0.02 mm) gets
// its fraction from exact distances, not from sampled signs. When several fields cross one leaf,
// the depth field is still integrated exactly per 4³ sub-cell, the others are sampled at the
// sub-cell centres. For meshes with holes, a cell whose centre winding number lies in (0.1, 0.9) is
// also treated as crossed (the w = 1/2 surface spans the hole, away from any triangle).
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "sinew/common/math.hpp"
#include "sinew/formats/model.hpp"
#include "sinew/voxelizer/distance.hpp"
#include "sinew/voxelizer/mesh.hpp"
#include "sinew/voxelizer/spec.hpp"
#include "sinew/voxelizer/winding_number.hpp"

namespace sinew::voxelizer {

// Signed distance to a mesh, positive inside, with its gradient. Thread-safe.
// Inside/outside: for a watertight mesh (closed, manifold, consistently and outward oriented, not
// intersecting itself) the sign of (p - closest)·n with n the angle-weighted pseudonormal of the
// closest feature (face, edge or vertex; Bærentzen & Aanæs 2005), which is exact there and
// cheaper; otherwise the generalized winding number w >= 1/2.
class SignedField {
 public:
  // watertight: the caller's verdict from clean_mesh (closed, no non-manifold or misoriented
  // edges, positive enclosed volume) and self_intersects (false: self_intersection.hpp; a folded
  // mesh passes clean_mesh's tests but not this one). closed: no boundary edges.
  SignedField(const TriangleMesh& mesh, bool watertight, bool closed);
  struct Sample {
    double value = 0;         // m, +dist inside, -dist outside
    double winding = 0;       // generalized winding number (0 or 1 when the pseudonormal decided)
    Vec3d gradient{0, 0, 0};  // unit, ∇value
    std::int32_t triangle = -1;  // closest triangle
  };
  Sample operator()(const Vec3d& p) const;
  // Inside test alone (same rule as the sign of operator()).
  bool inside(const Vec3d& p) const;
  const BoundingBox& bounds() const { return bounds_; }
  const WindingNumber& winding() const { return winding_; }
  const DistanceQuery& distance() const { return distance_; }
  const TriangleMesh& mesh() const { return mesh_; }
  bool closed() const { return closed_; }
  bool watertight() const { return watertight_; }

 private:
  bool pseudonormal_inside(const Vec3d& p, const DistanceQuery::Hit& hit) const;
  TriangleMesh mesh_;
  WindingNumber winding_;
  DistanceQuery distance_;
  BoundingBox bounds_;
  bool watertight_ = false, closed_ = false;
  std::vector<Vec3d> face_normal_;                 // unit
  std::vector<std::array<Vec3d, 3>> edge_normal_;  // per triangle, edge (k, k+1)
  std::vector<Vec3d> vertex_normal_;               // angle-weighted
};

// Volume of {u ∈ [0,1]³ : n·u < tau}, exactly (piecewise cubic in tau); any n, including zero
// components. Result in [0, 1].
double cube_fraction_below(const Vec3d& n, double tau);

struct FractionProblem {
  const SignedField* outer = nullptr;  // the skin: depth = outer value
  // Depth (m) of the bottom of each layer but the last (the last reaches everywhere deeper);
  // increasing. Layer i has label 1 + i.
  std::vector<double> layer_bottoms;
  int layer_count = 1;
  const SignedField* inner = nullptr;  // optional skull: no tissue inside it
  struct Body {
    const SignedField* field = nullptr;  // a closed mesh, or
    std::optional<Box> box;              // an axis-aligned box
    int label = 0;                       // > layer_count
  };
  std::vector<Body> bodies;  // increasing precedence: a later body overrides an earlier one
  int label_count = 2;       // labels are 0 .. label_count-1
  formats::VoxelGrid grid;
  int max_subdivision = 2;
  double min_tissue_fraction = 0;  // voxels whose tissue fraction is <= this (and <= 1e-12) drop
};

// Present voxels in lattice order (k, then j, then i), each with its labels' fractions (CSR;
// labels increasing, label 0 omitted, fractions > 1e-12).
struct VoxelFractions {
  std::vector<formats::Lattice> voxels;
  std::vector<std::int64_t> offsets{0};
  std::vector<std::int32_t> labels;
  std::vector<double> fractions;
  std::int64_t field_evaluations = 0;  // for the summary
};

// Computes the fractions of every voxel of problem.grid (OpenMP over blocks of 8³ voxels; the
// result does not depend on the thread count). progress(done, total) is called from one thread.
VoxelFractions compute_fractions(
    const FractionProblem& problem,
    const std::function<void(std::int64_t, std::int64_t)>& progress = {});

// The centre of voxel l of grid g (m).
Vec3d voxel_centre(const formats::VoxelGrid& g, const formats::Lattice& l);

// Removes the voxels whose centre (m) `drop` selects, their fractions with them (order kept);
// returns how many were removed.
std::int64_t drop_voxels(VoxelFractions& f, const formats::VoxelGrid& grid,
                         const std::function<bool(const Vec3d&)>& drop);

}  // namespace sinew::voxelizer
