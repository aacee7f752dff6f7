#pragma once
// The RESOLVED engine input: everything the engine needs besides the Model, with node ids already
// chosen, effects as explicit flags and every default filled in. sim-io maps a scene file onto it
// (resolve_scene); tests and benchmarks build it directly. docs/physics.md explains the physics of
// each field. SI units: metres, kilograms, seconds, newtons, pascals.
//
// What the engine does with it (one step n -> n+1, docs/physics.md "Step"):
//   element stresses/forces (+ hourglass, + muscles) -> per-node gather -> external forces
//   -> central-difference update -> sliding surfaces -> sliding planes -> prescribed -> jaw
//   -> rigid.
// An effect that is off allocates and computes nothing (see Plan::explain()).
#include <algorithm>
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sinew/formats/model.hpp"
#include "sinew/simulator/engine/curve.hpp"
#include "sinew/simulator/physics/jaw.hpp"

namespace sinew::simulator {

using Index = formats::Index;
using Vec3d = std::array<double, 3>;

// Same names and enumerators as the scene's (sim-io uses these).
enum class Precision { float32, float64 };
// Hourglass modulus M*: shear = 2μ (default; does not lock bending as ν -> 0.5, physics-notes §3),
// p_wave = λ + 2μ (NiftySim).
enum class HourglassModulus { shear, p_wave };

// The effects to simulate. Rigid nodes, sliding planes (symmetry conditions) and initial velocities
// are always honoured when listed; they are boundary conditions, not effects.
struct Effects {
  bool elasticity = true;  // neo-Hookean element stresses (off: only hourglass/muscles resist)
  bool hourglass = true;   // stiffness-based hourglass control (Joldes et al. 2008)
  bool damping = false;    // mass-proportional damping C = αM
  bool gravity = false;    // body force ρ g (physical ρ: mass scaling adds inertia, not weight)
  bool muscles = false;    // muscle fibre stresses (active + passive)
  bool sliding = false;    // the model's sliding bindings (nodes at rest distance from a surface)
  bool loads = false;      // prescribed displacements and nodal forces below
  bool contact = false;    // the lips' contact (the model's /jaw/lip_pairs, Setup::lip_contact)
};

enum class TimeStepPolicy {
  automatic,  // Δt = safety_factor × Δt_crit (the model's critical estimate, time_step.hpp)
  user,       // Δt = user_dt; refused (ConfigError) when above safety_factor × Δt_crit
  forced,     // Δt = user_dt whatever the estimate (reported as a warning)
};

struct TimeStep {
  TimeStepPolicy policy = TimeStepPolicy::automatic;
  // Applied to Δt_crit = min_e h / c_d,e (time_step.hpp). NOTE: Δt_crit is the Courant length
  // h / c_d, not the true limit: a free block of one-point cubes goes unstable near 0.85 h / c_d
  // at ν = 0.49 (physics-notes §4) and compression lowers it further, so factors above ~0.8 are
  // unsafe. Default 0.5.
  double safety_factor = 0.5;
  double user_dt = 0;  // s, for user / forced
};

struct Hourglass {
  double kappa = 0.075;  // κHG, dimensionless
  HourglassModulus modulus = HourglassModulus::shear;
};

// Prescribed displacement on a node set: u_i(t) = value_i · curve(t) for each selected component i;
// unselected components are free.
struct PrescribedDisplacement {
  std::vector<Index> nodes;
  std::array<bool, 3> components{true, true, true};
  Vec3d value{0, 0, 0};  // m, the displacement where the curve is 1
  Curve curve;           // empty: constant 1
  std::string label{};   // how stop messages name it, e.g. "boundary[2] (displacement of 'top')"
};

// External force on a node set: every node gets (total / nodes.size()) · curve(t).
struct NodalForce {
  std::vector<Index> nodes;
  Vec3d total{0, 0, 0};  // N, total over the set where the curve is 1
  Curve curve;           // empty: constant 1
  std::string label{};   // how stop messages name it
};

// Symmetry condition: each node stays on the plane through its REST position with this normal
// (its displacement has no component along the normal).
struct SlidingPlane {
  std::vector<Index> nodes;
  Vec3d normal{1, 0, 0};  // need not be unit; normalised by the engine
  std::string label{};    // how stop messages name it
};

// The jaw (the model's /jaw, physics/jaw.hpp) driven by curves: its nodes move as one rigid body,
// x' = R(θ(t))(x − pivot) + pivot + protrusion(t) · forward + lateral(t) · axis, every step. An
// empty curve is 0. Always honoured when present (a boundary condition, as rigid nodes).
struct JawMotion {
  std::vector<Index> nodes;   // sorted, unique; neither rigid, sliding nor prescribed
  Vec3d pivot{0, 0, 0};       // m
  Vec3d axis{1, 0, 0};        // unit, the subject's left
  Vec3d forward{0, 0, 1};     // unit, normal to axis
  Vec3d incisal{0, 0, 0};     // m, the incisal point at rest (the opening's report)
  Curve opening;              // rad about +axis
  Curve protrusion, lateral;  // m
  std::string label{"jaw"};   // how stop messages name it

  // The pose at curve time t (scene time: Setup::time_scaling already divided out).
  physics::JawPose pose(double t) const {
    const auto at = [t](const Curve& c) { return c.points.empty() ? 0.0 : c.at(t); };
    return {at(opening), at(protrusion), at(lateral)};
  }
  // The displacement map of pose(t) (physics/jaw.hpp): u = M (x − pivot) + d of a jaw node.
  void map(double t, double (&out)[physics::kJawMapSize]) const {
    const double p[3] = {pivot[0], pivot[1], pivot[2]}, a[3] = {axis[0], axis[1], axis[2]},
                 f[3] = {forward[0], forward[1], forward[2]};
    physics::jaw_displacement_map(p, a, f, pose(t), out);
  }
};

// Contact between the lips (physics/lip_contact.hpp): across each pair the upper node stays above
// the lower one along `up`. With effects.contact, from the model's /jaw/lip_pairs.
struct LipContact {
  std::vector<std::array<Index, 2>> pairs;  // upper, lower; each node once
  Vec3d up{0, 1, 0};                        // unit: the jaw's forward × axis
};

struct InitialVelocity {
  std::vector<Index> nodes;
  Vec3d velocity{0, 0, 0};  // m/s
};

struct Setup {
  Effects effects;
  Precision precision = Precision::float64;
  double duration = 0;  // s of simulated (scaled) time, see time_scaling
  TimeStep time_step;
  double damping_alpha = 0;  // α, 1/s; used when effects.damping
  // Mass scaling: every density is multiplied by this (≥ 1); Δt_crit grows by its square root.
  // Valid only when inertia does not matter; reported by the plan.
  double mass_scaling = 1;
  // Time scaling s ≥ 1: the motion is simulated s times slower. Every curve is read at t / s and
  // `duration` is the scaled (simulated) duration. Reported by the plan; sim-io divides output
  // times by s to give scene time.
  double time_scaling = 1;
  Hourglass hourglass;
  Vec3d gravity{0, 0, -9.81};  // m/s², with effects.gravity

  // Activation a(t) ∈ [0, 1] per model muscle, indexed like Model::muscles. Missing (shorter
  // vector) or empty curve: activation 0. Used when effects.muscles.
  std::vector<Curve> activation;

  // Nodes held at zero displacement. Exactly this list: the model's rigid_nodes are NOT added
  // implicitly (resolve_scene copies them in; tests choose).
  std::vector<Index> rigid_nodes;
  // Used when effects.loads.
  std::vector<PrescribedDisplacement> prescribed;
  std::vector<NodalForce> forces;
  // Steerable force slots of a live run (sinew-live, docs/live.md), used when effects.loads: each
  // is a force set after `forces` whose nodes and per-node force are set between steps
  // (Backend::set_force_slot); it starts empty and off. 0 in every batch run.
  int force_slots = 0;
  // A live run (sinew-live): activations may be overridden to any value in [0, 1] between steps
  // (BackendCore::set_activation_override), so the time step and the blow-up bound take every
  // muscle's peak as 1 (max_activation). false in every batch run.
  bool activation_overrides = false;
  // Always honoured.
  std::vector<SlidingPlane> sliding_planes;
  std::optional<JawMotion> jaw;
  std::optional<LipContact> lip_contact;
  std::vector<InitialVelocity> initial_velocities;
  // effects.sliding uses every binding in Model::sliding (no selection here).

  double output_interval = 0;  // s, for sim-io's writers; the engine does not use it

  // The largest activation muscle m can have in this run (the time step's and the blow-up
  // bound's): its curve's peak clamped to [0, 1] (0 without a curve), 1 with overrides.
  double max_activation(std::size_t m) const {
    if (activation_overrides) return 1.0;
    return m < activation.size() && !activation[m].points.empty()
               ? std::clamp(activation[m].max_value(), 0.0, 1.0)
               : 0.0;
  }

  // Energies are evaluated and the kinetic-energy blow-up test made every `energy_interval` steps
  // (and on request). NaN/Inf and J ≤ 0 are checked every step.
  int energy_interval = 10;
  // Blow-up: kinetic energy > blowup_factor × (initial energy + |external work| + peak strain
  // energy) + a floor (docs/physics.md "Instability").
  double blowup_factor = 10;
  // OpenMP threads for the CPU backend; 0: OpenMP's default. Results do not depend on it.
  int threads = 0;
};

}  // namespace sinew::simulator
