#pragma once
// Boundary conditions and node sets on a voxel model's nodes (paper §4, physics-notes §5).
//  - rigid: the selected nodes keep zero displacement;
//  - sliding: the selected nodes keep their rest distance d_q from a surface (the skull) while free
//    to move along it; each binding stores d_q and the nearest triangle at rest.
// A node is selected by a condition when it is inside the surface (winding number >= 1/2, with
// `inside`), or at unsigned distance <= `within` from it, and, when a box is given, in the box.
// Conditions apply in order; a node already bound by an earlier condition is skipped (one
// constraint per node).
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sinew/formats/model.hpp"
#include "sinew/voxelizer/fractions.hpp"
#include "sinew/voxelizer/spec.hpp"

namespace sinew::voxelizer {

struct BoundaryCondition {
  BoundarySpec::Kind kind = BoundarySpec::Kind::rigid;
  const SignedField* surface = nullptr;  // null: a box-only rigid condition
  formats::Index surface_index = -1;     // sliding: index of that surface in model.surfaces
  bool inside = false;
  std::optional<double> within;  // m
  std::optional<Box> box;
};

struct ConstraintResult {
  std::vector<formats::Index> rigid;             // sorted, unique
  std::vector<formats::SlidingBinding> sliding;  // sorted by node
  std::vector<std::int64_t> per_condition;       // nodes bound by each condition
  std::vector<std::int32_t> condition;           // per node: the condition binding it, -1 none
};

// Whether `cond` selects the node at p (m) on its own, ignoring earlier conditions: in its box
// (when given) and inside its surface (with `inside`) or within `within` of it.
bool condition_selects(const BoundaryCondition& cond, const Vec3d& p);

// OpenMP over nodes; independent of the thread count.
ConstraintResult bind_constraints(const formats::Model& model,
                                  const std::vector<BoundaryCondition>& conditions);

// Nodes in `box` (when given) and at unsigned distance <= distance from `surface` (when given).
formats::NamedSet select_nodes(const formats::Model& model, const std::string& name,
                               const std::optional<Box>& box, const SignedField* surface,
                               double distance);

}  // namespace sinew::voxelizer
