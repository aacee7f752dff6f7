#pragma once
// What constrains a node of a run, in words, for the stop messages of BackendCore (one formatter
// for both engines): rigid (the model's rigid nodes, or a set the scene fixes), sliding on a named
// surface (with its rest distance, and whether the node lay behind the surface at rest: the
// sliding projection then moves it out through the surface, by twice its depth, at the first
// step; physics/sliding.hpp), prescribed displacements, nodal forces and planes (by the scene's
// label). An element that inverts in the first steps of a run was inverted by its corners'
// constraints, not by the time step (docs/physics.md, "Instability").
#include <string>
#include <vector>

#include "sinew/simulator/engine/prepared_model.hpp"
#include "sinew/simulator/engine/setup.hpp"

namespace sinew::simulator {

// Steps from the start within which an inversion of a constrained element is blamed on its
// constraints: in 20 steps at the default safety factor 0.5 a wave crosses 10 elements, too few
// for dynamics started from rest to invert a cube without a contradictory constraint.
inline constexpr std::int64_t kConstraintBlameSteps = 20;

struct NodeConstraints {
  std::vector<std::string> items;  // e.g. "sliding on 'inner' (rest distance 0.41 mm; ...)"
  bool behind = false;             // a sliding binding that lay behind its surface at rest
};

// model_rigid: the model's rigid nodes (sorted), to tell them from the scene's fixed sets.
NodeConstraints node_constraints(const PreparedModel& p, const Setup& setup,
                                 const std::vector<Index>& model_rigid, Index node);

// "node 12 rigid (the model's rigid nodes); node 13 sliding on 'inner' (...)" over the element's
// corners ("" when none is constrained); behind: set when a corner lay behind its sliding surface.
std::string element_constraints(const PreparedModel& p, const Setup& setup,
                                const std::vector<Index>& model_rigid, Index element, bool& behind);

}  // namespace sinew::simulator
