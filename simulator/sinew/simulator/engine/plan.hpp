#pragma once
// The execution plan: from a Model and a resolved Setup, what the engine will compute and store.
//  - stages in order (only those the effects need),
//  - element collections grouped by what they compute (paper §6.1, Fig. 4): single-material
//    elements (their parameters are one shared row of the material table) and multi-material or
//    partly filled elements (a row of their own with the weighted moduli), each with and without
//    muscle fibres,
//  - every array the backend allocates with its size (an effect that is off has none),
//  - the time step and why it was chosen (time_step.hpp).
// make_plan validates the Setup against the Model and throws ConfigError naming the Setup field.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "sinew/formats/model.hpp"
#include "sinew/simulator/engine/setup.hpp"

namespace sinew::simulator {

struct PlanArray {
  std::string name;   // e.g. "displacement u(n)"
  std::string shape;  // e.g. "N × 3 float"
  std::size_t bytes = 0;
};

struct PlanStage {
  std::string name;    // e.g. "element stress + forces"
  std::string detail;  // what it covers, e.g. "4 collections, 125000 elements"
};

struct ElementCollection {
  std::string name;             // e.g. "single-material, no muscle"
  bool multi_material = false;  // per-element weighted moduli (own parameter row)
  bool muscle = false;          // elements with muscle fibres (only when muscles are simulated)
  std::vector<Index> elements;  // element ids, ascending
};

// One row of the element parameter table: the element's weighted moduli and density.
struct ParameterRow {
  double mu = 0;           // Σ w μ, Pa
  double kappa = 0;        // Σ w κ, Pa
  double p_wave = 0;       // Σ w (λ + 2μ), Pa
  double density = 0;      // Σ w ρ · mass_scaling, kg/m³
  double hourglass_k = 0;  // κHG · M* · 3h/16, N/m (0 when hourglass is off)
};

struct Plan {
  Precision precision = Precision::float64;
  std::size_t node_count = 0, element_count = 0;
  double voxel_size = 0;  // h, m
  Effects effects;

  std::vector<ElementCollection> collections;  // non-empty ones only
  std::vector<ParameterRow> parameters;     // rows 0..materials−1: the materials; then own rows
  std::vector<std::int32_t> parameter_row;  // E, row of each element
  std::size_t muscle_entries = 0;           // (element, muscle) pairs simulated
  std::size_t sliding_nodes = 0, sliding_triangles = 0;

  std::vector<PlanStage> stages;
  std::vector<PlanArray> arrays;

  double dt_critical = 0;          // s, min_e h / c_e
  Index dt_critical_element = -1;  // the element that sets it
  double dt = 0;                   // s, the step used
  std::int64_t steps = 0;          // ceil(duration / Δt)
  std::string dt_reason;           // one line: policy, factor, element
  std::vector<std::string> warnings;

  std::size_t total_bytes() const;
  std::string explain() const;  // the printable plan (sinew-simulate --explain)
};

// A time step above this share of h/c (the critical estimate) gets a plan warning: one-point
// hexahedra with lumped mass are stable only to about 0.85 h/c at ν = 0.49 (time_step.hpp).
inline constexpr double kSafeCourantShare = 0.8;

// mass_scaling above this is refused: Δt would grow by more than 10⁴ and the inertia be wrong by
// 10⁸, a value in the wrong unit rather than a choice (it also keeps the step estimate finite).
inline constexpr double kMaxMassScaling = 1e8;

// Throws ConfigError (file "", field = the Setup field, e.g. "time_step.user_dt") on bad input:
// ids out of range, Δt above the estimate without `forced`, non-positive duration, densities ≤ 0 …
Plan make_plan(const formats::Model& model, const Setup& setup);

}  // namespace sinew::simulator
