#pragma once
// Checks of a spec's boundary conditions once they are bound to the model's nodes
// (docs/voxelizer.md, "Safe constraints"). The simulator keeps a sliding node at its rest distance
// on the OUTER side of its surface (physics/sliding.hpp, physics-notes §5): a node bound while it
// lies behind the surface (inside the skull, say) is moved out through it, by twice its depth, at
// the first step, and the elements around it invert. So:
//  - error: a sliding condition binds nodes that lie behind their surface at rest (behind the
//    outward normal of their closest triangle, the simulator's test, by more than 1e-6 h, and
//    inside the surface by its own inside test; behind a triangle but outside the surface — a
//    misoriented or folded triangle of a messy mesh — is a warning with the count). The
//    message names the condition, the count, the deepest node and its depth, and every later
//    rigid condition that would have held those nodes (a sliding condition listed before
//    `rigid inside`);
//  - warning: elements with a corner held rigid by a condition on a surface next to a corner sliding
//    on the same surface (the rigid skull's nodes next to the deep layer sliding over it: such an
//    element cannot follow the tissue that slides past its rigid corner; docs/forehead.md), counted
//    per pair of conditions.
#include <string>
#include <vector>

#include "sinew/formats/model.hpp"
#include "sinew/voxelizer/constraints.hpp"
#include "sinew/voxelizer/spec.hpp"

namespace sinew::voxelizer {

// "sliding on 'inner': within 1 mm of 'inner', in its box": what a condition selects.
std::string describe_selection(const BoundarySpec& spec);
// "boundary[1] (sliding on 'inner': ...)": how messages name a condition.
std::string describe_condition(const BoundarySpec& spec);

struct ConstraintCheck {
  std::string field;  // the contradicting condition's key path ("" when none)
  std::string error;  // its message ("" when none)
  std::vector<std::string> warnings;
};

// conditions[i] was built from specs[i]; bound: what bind_constraints returned for them.
ConstraintCheck check_constraints(const formats::Model& model,
                                  const std::vector<BoundaryCondition>& conditions,
                                  const std::vector<BoundarySpec>& specs,
                                  const ConstraintResult& bound);

}  // namespace sinew::voxelizer
