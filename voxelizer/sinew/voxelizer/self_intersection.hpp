#pragma once
// Whether a closed triangle mesh intersects itself: two of its triangles that share no corner
// meet, or two that share one cross elsewhere (CGAL Polygon Mesh Processing's does_self_intersect,
// exact predicates). A mesh that folds over itself can be closed, manifold, consistently and
// outward oriented and enclose a positive volume, and still not bound one region: there the sign
// of the closest feature's pseudonormal (fractions.hpp's inside test for watertight meshes) is
// wrong near the fold, and the voxelizer must fall back to the generalized winding number.
#include "sinew/voxelizer/mesh.hpp"

namespace sinew::voxelizer {

// True when `mesh` (closed and manifold: clean_mesh's `closed`) intersects itself. A mesh that is
// not closed and manifold is not tested and gives false.
bool self_intersects(const TriangleMesh& mesh);

}  // namespace sinew::voxelizer
