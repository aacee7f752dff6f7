#pragma once
// The backend core: everything the CPU and CUDA engines share besides their loops (docs/
// development.md, "Architecture"). Each engine keeps only its storage and scheduling:
//  - EngineArrays<T>: the typed arrays of a run, built once from the prepared model (named structs
//    from PreparedModel to the loop bodies: physics::ElementRow, physics::MuscleParams, the
//    constraint program, the sliding tables). The CPU engine runs on them; the CUDA engine uploads
//    them.
//  - BackendCore: the per-step scalars (activations, load and prescribed factors from the curves),
//    the instability diagnostics and their messages (one formatter; the GPU only fills a
//    StepStatus), the blow-up bound, restore checks, velocities, reactions, kinetic energy and
//    element fields.
// The one order of loads and constraints is the constraint program (passes/constraint_program.hpp)
// built here.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <vector>

#include "sinew/common/math.hpp"
#include "sinew/formats/model.hpp"
#include "sinew/simulator/engine/backend.hpp"
#include "sinew/simulator/engine/plan.hpp"
#include "sinew/simulator/engine/prepared_model.hpp"
#include "sinew/simulator/engine/setup.hpp"
#include "sinew/simulator/passes/constraint_program.hpp"
#include "sinew/simulator/passes/element_pass.hpp"
#include "sinew/simulator/passes/node_pass.hpp"
#include "sinew/simulator/passes/sliding_lists.hpp"
#include "sinew/simulator/passes/step_status.hpp"

namespace sinew::simulator {

// One sliding surface in the run's scalar: geometry, normals, the static grid and its query tables
// (sliding_grid.hpp), per-triangle corners for the listed tests, and the lists' skin.
template <typename T>
struct SlidingSurfaceArrays {
  std::vector<Vec3<T>> vertices, normals;  // m; unit outward normal per triangle
  std::vector<std::array<std::int32_t, 3>> triangles;
  SurfaceGrid grid;
  SurfaceLists<T> lists;                  // make_surface_lists(grid, vertices, triangles)
  std::vector<Vec3<T>> triangle_corners;  // triangle_corner_list: 3 per triangle
  T skin = T(0);                          // s of the candidate lists, m
  // The query view over these host arrays (the CUDA engine builds its own over device copies).
  SurfaceView<T> view() const;
};

// The constraint program (passes/constraint_program.hpp) and the tables its ops read.
template <typename T>
struct ConstraintArrays {
  std::vector<std::int32_t> node, offset, op;  // C constrained nodes, C + 1, their ops
  std::vector<std::int32_t> node_op_offset;    // N + 1: node i's ops (the node and tile kernels)
  std::vector<Vec3<T>> force_per_node;         // per force set, N
  std::vector<std::int32_t> prescribed_set;    // per prescribed entry
  std::vector<Vec3<T>> prescribed_value;       // per prescribed set, m
  std::vector<std::int32_t> prescribed_mask;   // per prescribed set, bit c: component c
  std::vector<Vec3<T>> plane_normal;           // per plane entry, unit
  std::int32_t jaw_factor = -1;                // ConstraintData::jaw_factor
  std::vector<std::int32_t> contact_partner;   // per contact entry (ConstraintData)
  std::vector<T> contact_share;                // per contact entry, σ s
  Vec3<T> contact_up{T(0), T(0), T(0)};        // unit
};

// The typed arrays of a run in scalar T (T(x) of the prepared doubles, as both engines always did,
// so both start from bit-identical inputs).
template <typename T>
struct EngineArrays {
  T h = T(0);  // m
  std::size_t nodes = 0, elements = 0;
  std::vector<std::array<Index, 8>> element_nodes;  // E × 8
  std::vector<std::int32_t> row;                    // E
  std::vector<physics::ElementRow<T>> rows;
  std::vector<Vec3<T>> rest;     // N, m
  std::vector<T> inverse_mass;   // N, 1/kg
  std::vector<Vec3<T>> gravity;  // N, N (empty without gravity)
  // Node -> element corner incidence, entries e · 8 + corner in the fixed gather order.
  std::vector<std::int32_t> incidence_offset, incidence;
  // Muscles (empty unless simulated): CSR over elements.
  std::vector<std::int32_t> muscle_offset, muscle_id;
  std::vector<T> muscle_fraction;
  std::vector<Vec3<T>> muscle_fibre;
  std::vector<physics::MuscleParams<T>> muscle_params;
  ConstraintArrays<T> constraints;
  // Sliding (empty unless simulated): surfaces, and per binding its node, surface, rest distance
  // and closest triangle at rest.
  std::vector<SlidingSurfaceArrays<T>> surfaces;
  std::vector<std::int32_t> slide_node, slide_surface, slide_triangle;
  std::vector<T> slide_distance;

  // Views over these host arrays. activation: per model muscle (may be null without muscles).
  ElementData<T> element_data() const;
  NodeData<T> node_data(const physics::CentralDifference<T>& cd) const;
};

// sliding_skin: s of the candidate lists in grid cells of each surface (> 0).
template <typename T>
EngineArrays<T> make_engine_arrays(const PreparedModel& p, double sliding_skin);
// The constraint program of `p` (EngineArrays::constraints; rebuilt when a live force slot changes).
template <typename T>
ConstraintArrays<T> make_constraint_program(const PreparedModel& p);

// The sliding state of a run in host memory (the CPU engines): per binding its closest triangle, the
// warm start of its grid searches, its candidate list and the list's anchor (passes/
// sliding_lists.hpp), refreshed inline as the node moves; and the surfaces' query views.
template <typename T>
struct HostSlidingState {
  std::vector<SlideSurface<T>> surfaces;
  std::vector<std::int32_t> triangle, search_triangle, list_count, list;
  std::vector<T> list_distance;
  std::vector<Vec3<T>> anchor;

  HostSlidingState() = default;
  explicit HostSlidingState(const EngineArrays<T>& a);  // the triangles at rest, no lists
  // Continues from these closest triangles; the lists are a cache: the grid search gives the same.
  void restore(const std::vector<Index>& triangles);
  SlideData<T> data(const EngineArrays<T>& a);
};

// The constraint program's view over host arrays (the CPU engines): the tables of `a`, the engine's
// prescribed captures (per prescribed entry) and its sliding state.
template <typename T>
ConstraintData<T> host_constraint_data(const EngineArrays<T>& a,
                                       const physics::CentralDifference<T>& cd,
                                       Vec3<T>* prescribed_free, HostSlidingState<T>& sliding);

// N × 3 doubles, node-major, of n vectors in T (the Backend interface's layout), and back with T(x).
template <typename T>
std::vector<double> flatten(const Vec3<T>* v, std::size_t n);
template <typename T>
std::vector<Vec3<T>> unflatten(const std::vector<double>& flat);

class BackendCore {
 public:
  // Prepares the model (prepare_model). The plan must come from make_plan(model, setup).
  BackendCore(const formats::Model& model, const Setup& setup, Plan plan);

  const Setup& setup() const { return setup_; }
  const Plan& plan() const { return plan_; }
  const PreparedModel& prepared() const { return prepared_; }
  double dt() const { return plan_.dt; }
  std::size_t nodes() const { return prepared_.nodes; }
  std::size_t elements() const { return prepared_.elements; }
  double time(std::int64_t step) const { return double(step) * plan_.dt; }
  // Curves are read at t / time_scaling (Setup::time_scaling).
  double curve_time(double t) const { return t / setup_.time_scaling; }

  // Per-step scalars, one row per step: [activation a_m(t_n) clamped to [0, 1] (muscles) | force
  // factors at t_n (force sets) | prescribed factors at t_n+1 (prescribed sets) | the jaw's map at
  // t_n+1 (physics::kJawMapSize, with a jaw)]. A step of −1 gives the prescribed factors and the
  // jaw at t = 0 (the initial constraints).
  std::size_t muscle_count() const { return setup_.effects.muscles ? muscle_count_ : 0; }
  std::size_t step_scalar_count() const;
  template <typename T>
  void step_scalars(std::int64_t step, T* row) const;
  template <typename T>
  void activations(double t, T* out) const;  // muscle_count() values at time t
  // The jaw's displacement map at simulated time t (its curves at t / time_scaling; needs a jaw).
  void jaw_map(double t, double (&map)[physics::kJawMapSize]) const;

  // Steering (sinew-live, docs/live.md): changes between steps, read by step_scalars, so both
  // engines see them from their next step() call. The plan is never rebuilt.
  // Activation override of muscle m (model order), set between steps at step `step`: from there
  // the activation ramps linearly, over override_ramp_steps(Δt) steps (kOverrideRampSeconds of
  // simulated time), from the value step `step` had to a ∈ [0, 1], or to the curve's value
  // (nullopt, back to the curve); ramped_activation gives step n's value. An instant jump, e.g.
  // from 0.05 early in a scene's ramp to its peak, inverted elements of the 0.5 mm forehead beside
  // its sliding scalp in float and double (docs/performance.md, "Live"); a muscle takes tens of
  // ms to activate. A step before the current override's (a restore went back) sets it at once.
  // Throws ConfigError for m out of range, a not finite, or a above Setup::max_activation(m) (the
  // time step was planned for that; a live run sets Setup::activation_overrides, which makes it 1).
  void set_activation_override(std::size_t m, std::optional<double> a, std::int64_t step);
  std::optional<double> activation_override(std::size_t m) const;  // the target, if any
  static constexpr double kOverrideRampSeconds = 0.03;
  static std::int64_t override_ramp_steps(double dt) {
    return std::max<std::int64_t>(1, std::llround(kOverrideRampSeconds / dt));
  }
  // A scene curve's activation at curve time t: clamped to [0, 1]; 0 for an empty curve.
  static double clamped_activation(const Curve& c, double t) {
    return c.points.empty() ? 0.0 : std::clamp(c.at(t), 0.0, 1.0);
  }
  // Step n's activation under an override set at step `start` with this ramp (steps), from
  // `from` to `target`: target from start + ramp on, else from + (target − from) (n − start) /
  // ramp. The live reproduction (live/steering_log.cpp) evaluates its steps with this too.
  static double ramped_activation(double from, double target, std::int64_t start, std::int64_t ramp,
                                  std::int64_t n) {
    if (n >= start + ramp || n < start) return target;
    return from + (target - from) * (double(n - start) / double(ramp));
  }
  // Live force slots (Setup::force_slots): force sets after the scene's. set_force_slot gives slot
  // k these nodes (ids checked) and per-node force (N, finite), factor 1; clear_force_slot empties
  // it (factor 0). The engine must then rebuild its constraint program (make_constraint_program).
  std::size_t force_slot_count() const { return force_slots_; }
  void set_force_slot(std::size_t k, std::vector<Index> nodes, const std::array<double, 3>& force);
  void clear_force_slot(std::size_t k);

  // Instability: the blow-up bound (docs/physics.md, "Instability") for scalar epsilon `eps`.
  void set_initial_energy(const Energies& e0);
  void set_energy_reference(double reference) { initial_energy_ = reference; }
  double energy_reference() const { return initial_energy_; }
  BlowupBound blowup_bound() const;  // base without the work
  double blowup_reference(double work) const;
  bool blown_up(double kinetic, double strain_and_hourglass, double work) const;

  // The messages: each throws InstabilityError naming step, time, the element or node, its rest
  // position and what to do. fail_element names the constraints of the element's corners
  // (constraint_report.hpp) and, in the first kConstraintBlameSteps steps or when a sliding corner
  // lay behind its surface, blames them instead of the time step.
  [[noreturn]] void fail_element(std::int64_t step, Index element, double j) const;
  [[noreturn]] void fail_displacement(std::int64_t step, Index node) const;  // step: the new one
  [[noreturn]] void fail_blowup(std::int64_t step, double kinetic, double work, Index fastest,
                                double speed) const;

  // Throws ConfigError (field `what`) when a node id is out of range.
  void check_node_ids(const std::vector<Index>& nodes, const char* what) const;
  // The checkpoint state of a run at `step` (State; energy_reference from this core).
  template <typename T>
  State make_state(std::int64_t step, const std::vector<Vec3<T>>& u, const std::vector<Vec3<T>>& up,
                   std::vector<Index> sliding_triangle, double external_work) const;
  // Checks a state against this run; throws ConfigError naming the state's field. Node count,
  // Δt (exactly this run's), step ≥ 0, |time − step · Δt| ≤ kStateTimeTolerance · max(step · Δt,
  // Δt), sliding triangle ids inside their surfaces, finite displacements. Not the step against
  // plan().steps: engines step on past the plan (tests, a live session); a restart checks that.
  void check_state(const State& s) const;

  // The kinetic energy at (u, up), J: per node node_kinetic_energy, summed per chunk of 1024 nodes
  // and the chunks in order (any thread count gives the same bits). threads ≤ 0: OpenMP's default.
  template <typename T>
  double kinetic_energy(const Vec3<T>* u, const Vec3<T>* up, const T* inverse_mass,
                        int threads) const;
  // The fastest node (the first NaN, else the largest |u − up|; its |u − up|²).
  template <typename T>
  Index fastest_node(const Vec3<T>* u, const Vec3<T>* up, double& squared_move) const;
  // The first node whose displacement is not finite (−1: none).
  template <typename T>
  Index first_non_finite(const Vec3<T>* u) const;
  // The worst element at u: the first NaN J, else the smallest (lowest id on ties); its J.
  template <typename T>
  Index worst_element(const EngineArrays<T>& a, const Vec3<T>* u, double& j) const;
  template <typename T>
  std::vector<double> velocities(const Vec3<T>* u, const Vec3<T>* up) const;  // N × 3, m/s
  // Σ over `nodes` of (internal force − gravity − nodal forces at t_n), N (Backend::reaction);
  // set_forces[k]: the internal force of nodes[k] (a node listed twice counts twice).
  template <typename T>
  std::array<double, 3> reaction(const EngineArrays<T>& a, const std::vector<Index>& nodes,
                                 const Vec3<T>* set_forces, std::int64_t step) const;
  // Per-element output fields at u (Backend::element_fields) with the activations of `step`,
  // threads as kinetic_energy.
  template <typename T>
  ElementFields element_fields(const EngineArrays<T>& a, const Vec3<T>* u, std::int64_t step,
                               int threads) const;
  // The same fields, computed later by the returned function from this copy of u and the
  // activations of `step` read now (Frame::fields); `a` and this core must outlive it.
  template <typename T>
  std::function<ElementFields()> deferred_element_fields(const EngineArrays<T>& a,
                                                         std::vector<Vec3<T>> u, std::int64_t step,
                                                         int threads) const;

 private:
  // element_fields with the activations given (muscle_count() values).
  template <typename T>
  ElementFields fields_at(const EngineArrays<T>& a, const Vec3<T>* u, const T* activation,
                          int threads) const;

  Setup setup_;
  Plan plan_;
  PreparedModel prepared_;
  std::vector<Index> model_rigid_;  // the model's rigid nodes, for the stop messages
  std::size_t muscle_count_ = 0;
  struct ActivationOverride {
    std::optional<double> target;  // none: back to the curve
    double from = 0;               // the activation of step `start` before the change
    std::int64_t start = 0, ramp = 0;
  };
  std::vector<std::optional<ActivationOverride>> activation_override_;  // per muscle
  double curve_activation(std::size_t m, double t) const;               // the scene's, clamped
  double activation_value(std::size_t m, std::int64_t step) const;      // with the override
  std::size_t force_slots_ = 0;  // the last entries of prepared_.forces
  // J, ε · volume · min modulus (the strain energy's round-off) + ½ · total mass · (ε · max |x| /
  // Δt)² (the kinetic energy of positions moving by their own round-off each step); docs/physics.md
  // "Instability".
  double energy_floor_ = 0;
  double initial_energy_ = 0;  // J, max(0, initial kinetic + strain + hourglass energy)
};

}  // namespace sinew::simulator
