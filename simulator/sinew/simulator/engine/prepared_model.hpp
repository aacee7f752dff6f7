#pragma once
// Host-side preparation shared by the backends: everything derived once from (Model, Setup, Plan)
// before a run, in double, as named structs; make_engine_arrays (backend_core.hpp) converts it to
// the run's scalar T with T(x) once for both engines, so both start from bit-identical inputs.
// Arrays are flat (CSR where ragged) so they copy to a device as they are.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "sinew/formats/model.hpp"
#include "sinew/simulator/engine/curve.hpp"
#include "sinew/simulator/engine/plan.hpp"
#include "sinew/simulator/engine/setup.hpp"
#include "sinew/simulator/passes/sliding_grid.hpp"
#include "sinew/simulator/physics/element.hpp"

namespace sinew::simulator {

struct PreparedLoadSet {
  std::vector<Index> nodes;
  std::array<double, 3> per_node{0, 0, 0};  // N per node (forces) or m (prescribed value)
  std::array<bool, 3> components{true, true, true};
  Curve curve;
};

struct PreparedSurface {
  std::string name;                                    // the model surface's
  std::vector<std::array<double, 3>> vertices;         // m
  std::vector<std::array<std::int32_t, 3>> triangles;  // validated ids
  SurfaceGrid grid;                                    // built once
};

struct PreparedModel {
  std::size_t nodes = 0, elements = 0;
  double h = 0;                                     // m
  std::vector<std::array<Index, 8>> element_nodes;  // E × 8
  std::vector<std::int32_t> row;                    // E, parameter row of each element
  std::vector<physics::ElementRow<double>> rows;    // per row; μ = κ = 0 without elasticity
  std::vector<std::array<double, 3>> rest;          // N, m
  std::vector<Index> dominant_material;             // E
  std::vector<double> mass;                         // N, kg (mass-scaled)
  std::vector<std::array<double, 3>> gravity;  // N, the physical weight (empty without gravity)
  double volume = 0, min_modulus = 1;          // for the energy floor ε · volume · min_modulus
  // Node -> (element, corner) incidence, ascending element order: the fixed gather order.
  std::vector<std::int64_t> incidence_offset;  // N + 1
  std::vector<std::int32_t> incidence;         // E × 8, entries e · 8 + corner
  // Muscles (empty unless simulated): CSR over elements.
  std::vector<std::int64_t> muscle_offset;  // E + 1
  std::vector<std::int32_t> muscle_id;
  std::vector<double> muscle_fraction;
  std::vector<std::array<double, 3>> muscle_fibre;           // unit
  std::vector<physics::MuscleParams<double>> muscle_params;  // per model muscle
  double active_energy_bound = 0;                            // J
  // Loads (empty unless effects.loads), planes, rigid nodes.
  std::vector<PreparedLoadSet> forces, prescribed;
  std::vector<Index> plane_nodes;
  std::vector<std::array<double, 3>> plane_normals;  // unit
  std::vector<Index> rigid;
  // The jaw (Setup::jaw): its nodes; empty without one.
  std::vector<Index> jaw_nodes;
  // Lip contact (Setup::lip_contact): one entry per free node of a pair (physics/lip_contact.hpp):
  // the node, its partner, σ s (σ = +1 upper, −1 lower; s = ½, or 1 when the partner is held).
  std::vector<Index> contact_node, contact_partner;
  std::vector<double> contact_share;
  std::array<double, 3> contact_up{0, 0, 0};  // unit
  // Sliding (empty unless simulated): one surface per model surface in use; one entry per binding.
  std::vector<PreparedSurface> surfaces;
  std::vector<Index> slide_node;
  std::vector<std::int32_t> slide_surface;
  std::vector<double> slide_distance;
  std::vector<std::int32_t> slide_triangle;
};

// Throws ConfigError for zero fibres and triangle vertex ids out of range (as the CPU backend).
PreparedModel prepare_model(const formats::Model& model, const Setup& setup, const Plan& plan);

}  // namespace sinew::simulator
