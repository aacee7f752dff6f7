#pragma once
// The simulation engine's interface: an abstract Backend (what the runner and the tests call). The
// CPU backend (OpenMP, cpu_engine.hpp) and the CUDA backend (cuda_backend.hpp) implement it; both
// call the same physics functions (physics/element.hpp) on the same prepared data
// (prepared_model.hpp), through the core they share (backend_core.hpp).
//
// Step n -> n+1 (t_n = n·Δt, curves read at t_n / time_scaling):
//  1. per element: F, C, J, S (neo-Hookean + muscles), nodal forces V0 F S ∇N, + hourglass forces,
//     into a per-element force buffer (E × 8 × 3)
//  2. per node: gather its (element, corner) entries in a fixed order -> internal force f
//     (bit-identical for any thread count)
//  3. external forces R (nodal forces, gravity); central-difference update of every node
//  4. constraints: sliding surfaces, sliding planes, prescribed displacements, rigid nodes
// Instability: NaN/Inf or J ≤ 0 (checked every step) or kinetic-energy blow-up (every
// energy_interval steps) throws InstabilityError naming step, time, worst element/node and its
// position; the state stays at u(n), where the problem was found (nothing non-finite is accepted).
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "sinew/formats/model.hpp"
#include "sinew/simulator/engine/plan.hpp"
#include "sinew/simulator/engine/setup.hpp"
#include "sinew/simulator/engine/state.hpp"

namespace sinew::simulator {

struct Energies {
  std::int64_t step = 0;
  double time = 0;           // s
  double kinetic = 0;        // J, ½ Σ m |v|², v = (u(n) − u(n−1))/Δt
  double strain = 0;         // J, Σ_e V0 W_e (neo-Hookean + passive muscle + active at current a)
  double elastic = 0;        // J, the same without the active muscle term: the energy stored in
                             // the material (neo-Hookean + passive muscle, ≥ 0)
  double hourglass = 0;      // J, Σ_e ½ k Σ q²
  double external_work = 0;  // J, work of nodal forces, gravity and prescribed displacements
};

// Per-element output fields at the current state (E entries each).
struct ElementFields {
  std::vector<double> jacobian;               // J = det F
  std::vector<double> von_mises;              // Pa, von Mises stress of the Cauchy stress
  std::vector<std::array<double, 6>> cauchy;  // Pa, Cauchy stress σ = J⁻¹ F S Fᵀ, Voigt order
                                              // (xx, yy, zz, yz, xz, xy)
  std::vector<double> energy_density;         // J/m³ of reference volume (hourglass excluded)
  std::vector<Index> material;                // dominant material (largest fraction)
};

// What a results frame needs, taken at one step (Backend::frame). The element fields are computed
// later by `fields`, from a copy of u(n) and the step's activations taken with the frame, on any
// thread while the backend steps on (the runner writes frames in the background on the GPU). The
// backend must outlive `fields`; the result is exactly element_fields() at that step.
struct Frame {
  std::int64_t step = 0;
  double time = 0;                        // s, engine time (step · Δt)
  std::vector<double> displacements;      // N × 3, m, u(n)
  Energies energies;                      // energies() at the step
  std::function<ElementFields()> fields;  // empty unless asked for
};

class Backend {
 public:
  virtual ~Backend() = default;
  virtual std::string name() const = 0;  // "cpu"
  virtual const Plan& plan() const = 0;

  // Advances n steps. Throws InstabilityError; the state then stays at the step where the problem
  // was found (finite, readable, restorable).
  virtual void step(std::int64_t n) = 0;
  virtual std::int64_t step_index() const = 0;
  // How many steps a caller should ask of step() at a time when nothing falls due in between: the
  // CPU 64 (progress and interrupts stay responsive), the CUDA backend several graph batches (it
  // checks its queued steps once per call). Any count gives the same results.
  virtual std::int64_t preferred_step_count() const { return 64; }
  virtual double time() const = 0;  // s, step_index() · dt()
  virtual double dt() const = 0;

  virtual State state() const = 0;
  // Throws ConfigError when the state does not fit (node count, Δt, binding count).
  virtual void restore(const State& state) = 0;

  virtual std::vector<double> displacements() const = 0;  // N × 3, m, u(n)
  // u(n) of the listed nodes only, 3 per node in list order, m (probes: the CUDA backend gathers
  // them on the device and copies only these). Throws ConfigError for an id out of range.
  virtual std::vector<double> displacements(const std::vector<Index>& nodes) const = 0;
  virtual std::vector<double> velocities() const = 0;  // N × 3, m/s, (u(n) − u(n−1))/Δt
  // Internal nodal forces f at u(n), N × 3, N (computed on demand).
  virtual std::vector<double> internal_forces() = 0;
  // Reaction at u(n): Σ over the nodes of (internal force − external load at t_n: gravity, nodal
  // forces), N. At equilibrium this is the force the supports (constraints) exert on the body
  // there; e.g. P11 · A0 on a pulled face. A node listed twice counts twice.
  virtual std::array<double, 3> reaction(const std::vector<Index>& nodes) = 0;
  virtual Energies energies() = 0;
  virtual ElementFields element_fields() = 0;

  // Steering between steps (sinew-live, docs/live.md; BackendCore): from the next step() call.
  // Activation override of muscle m (nullopt: back to its curve), reached over a ramp of
  // BackendCore::kOverrideRampSeconds from the current step. Throws ConfigError.
  virtual void set_activation_override(std::size_t m, std::optional<double> a) = 0;
  virtual std::optional<double> activation_override(std::size_t m) const = 0;
  // Live force slot k (Setup::force_slots): these nodes each get `force` (N) until cleared.
  virtual std::size_t force_slot_count() const = 0;
  virtual void set_force_slot(std::size_t k, const std::vector<Index>& nodes,
                              const std::array<double, 3>& force) = 0;
  virtual void clear_force_slot(std::size_t k) = 0;
  // The frame at the current step: displacements and energies now, the element fields (when
  // `with_fields`) deferred (Frame).
  virtual Frame frame(bool with_fields) = 0;
  // True when step() leaves the host thread mostly waiting (the GPU), so frames are best written
  // by another thread meanwhile; false when stepping keeps every core busy (the CPU).
  virtual bool host_idle_while_stepping() const { return false; }
};

}  // namespace sinew::simulator
