#pragma once
// Binding visual surface vertices to the voxel model (paper §3: "bound surface meshes for visual
// purposes"). A vertex p in element e gets natural coordinates
//   ξ = 2 (p - X_e) / h - 1   (componentwise; X_e = the element's base corner, h = voxel size),
// so that the hex8 shape functions N_a(ξ) = ⅛ (1 + ξa ξ)(1 + ηa η)(1 + ζa ζ) reproduce
//   p = Σ_a N_a(ξ) X_a
// exactly (to rounding) for the axis-aligned voxel. A vertex on a face, edge or corner shared by
// several cells goes to the first present one in lattice order. A vertex in no present element is
// bound to the nearest present element (Euclidean distance to the element's box) with its
// coordinates clamped to [-1, 1] (its rest position is then the nearest point of that element);
// those are counted and reported.
#include <cstdint>
#include <vector>

#include "sinew/formats/model.hpp"

namespace sinew::voxelizer {

struct Embedding {
  std::vector<formats::Index> element;
  std::vector<formats::Point> local;
  std::int64_t outside = 0;         // vertices not in any present element
  double max_outside_distance = 0;  // m, the farthest of those from its element
};

// points: positions (m). OpenMP over points; independent of the thread count.
Embedding embed_points(const formats::Model& model, const std::vector<formats::Point>& points);

// Σ_a N_a(ξ) X_a for element e: the position reproduced by an embedding (m).
formats::Point embedded_position(const formats::Model& model, formats::Index element,
                                 const formats::Point& local);

}  // namespace sinew::voxelizer
