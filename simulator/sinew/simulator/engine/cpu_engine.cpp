#include "sinew/simulator/engine/cpu_engine.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "sinew/common/log.hpp"
#include "sinew/common/math.hpp"
#include "sinew/simulator/engine/backend_core.hpp"
#include "sinew/simulator/passes/constraint_program.hpp"
#include "sinew/simulator/passes/cpu_for_each.hpp"
#include "sinew/simulator/passes/effect_dispatch.hpp"
#include "sinew/simulator/passes/element_pass.hpp"
#include "sinew/simulator/passes/node_pass.hpp"

namespace sinew::simulator {
namespace {

// The smallest J of a chunk of elements (the first NaN wins; ties keep the lower element id, as
// chunks are merged in order) and its energies.
struct ElementCheck {
  double min_j = std::numeric_limits<double>::infinity();
  Index element = -1;
  double strain = 0, elastic = 0, hourglass = 0;
  void track(double j, Index e) {
    if (element < 0 || (!std::isnan(min_j) && (std::isnan(j) || j < min_j))) {
      min_j = j;
      element = e;
    }
  }
  void merge(const ElementCheck& o) {
    const bool o_nan = std::isnan(o.min_j), nan = std::isnan(min_j);
    if (o.element >= 0 && (element < 0 || (!nan && (o_nan || o.min_j < min_j)))) {
      min_j = o.min_j;
      element = o.element;
    }
    strain += o.strain;
    elastic += o.elastic;
    hourglass += o.hourglass;
  }
};

// The CPU engine: storage (host vectors) and scheduling (OpenMP chunks, passes/cpu_for_each.hpp)
// of the loop bodies in passes/, around the shared BackendCore.
template <typename T>
class CpuEngine final : public Backend {
 public:
  CpuEngine(const formats::Model& model, const Setup& setup, Plan plan);

  std::string name() const override { return "cpu"; }
  const Plan& plan() const override { return core_.plan(); }
  void step(std::int64_t n) override {
    for (std::int64_t k = 0; k < n; ++k) single_step();
  }
  std::int64_t step_index() const override { return step_; }
  double time() const override { return core_.time(step_); }
  double dt() const override { return core_.dt(); }
  State state() const override;
  void restore(const State& s) override;
  std::vector<double> displacements() const override { return flatten(u_.data(), n_); }
  std::vector<double> displacements(const std::vector<Index>& nodes) const override {
    core_.check_node_ids(nodes, "nodes");
    std::vector<Vec3<T>> picked;
    picked.reserve(nodes.size());
    for (auto n : nodes) picked.push_back(u_[std::size_t(n)]);
    return flatten(picked.data(), picked.size());
  }
  std::vector<double> velocities() const override {
    return core_.velocities(u_.data(), up_.data());
  }
  std::vector<double> internal_forces() override {
    ensure_forces(false);
    return flatten(f_.data(), n_);
  }
  std::array<double, 3> reaction(const std::vector<Index>& nodes) override {
    ensure_forces(false);
    core_.check_node_ids(nodes, "reaction");
    std::vector<Vec3<T>> set_forces;
    set_forces.reserve(nodes.size());
    for (auto n : nodes) set_forces.push_back(f_[std::size_t(n)]);
    return core_.reaction(a_, nodes, set_forces.data(), step_);
  }
  Energies energies() override;
  ElementFields element_fields() override {
    return core_.element_fields(a_, u_.data(), step_, threads_);
  }
  void set_activation_override(std::size_t m, std::optional<double> a) override {
    core_.set_activation_override(m, a, step_);
    forces_valid_ = energy_valid_ = false;  // forces at u(n) depend on the activation
  }
  std::optional<double> activation_override(std::size_t m) const override {
    return core_.activation_override(m);
  }
  std::size_t force_slot_count() const override { return core_.force_slot_count(); }
  void set_force_slot(std::size_t k, const std::vector<Index>& nodes,
                      const std::array<double, 3>& force) override {
    core_.set_force_slot(k, nodes, force);
    a_.constraints = make_constraint_program<T>(core_.prepared());
  }
  void clear_force_slot(std::size_t k) override {
    core_.clear_force_slot(k);
    a_.constraints = make_constraint_program<T>(core_.prepared());
  }
  Frame frame(bool with_fields) override {
    Frame f{step_, time(), displacements(), energies(), {}};
    if (with_fields) f.fields = core_.deferred_element_fields(a_, u_, step_, threads_);
    return f;
  }

 private:
  void ensure_forces(bool energy) {
    if (!forces_valid_ || (energy && !energy_valid_)) compute_forces(energy);
  }
  void compute_forces(bool energy);
  template <bool kElastic, bool kMuscle, bool kHourglass, bool kEnergy>
  ElementCheck element_pass(const std::vector<Index>& elements);
  template <bool kGravity>
  bool update_nodes();
  // Loads and constraints of u on the constraint program, with the factors of `step`
  // (step_scalars); `loads` off: the initial constraints (no forces, captures or work). Returns
  // the work of the loads and constraint forces over the step.
  double apply_constraints(std::vector<Vec3<T>>& u, std::int64_t step, bool loads);
  ConstraintData<T> constraint_data() {
    return host_constraint_data(a_, cd_, prescribed_free_.data(), sliding_);
  }
  void single_step();

  BackendCore core_;
  EngineArrays<T> a_;
  int threads_ = 1;
  std::size_t n_ = 0;
  physics::CentralDifference<T> cd_;
  std::vector<T> activation_, scalars_;
  std::vector<Vec3<T>> elem_force_, f_;   // E × 8 (element-major: e · 8 + corner), N
  std::vector<Vec3<T>> prescribed_free_;  // per prescribed entry: u* before constraints
  HostSlidingState<T> sliding_;
  // dynamic state
  std::vector<Vec3<T>> u_, up_, un_;
  std::int64_t step_ = 0;
  double external_work_ = 0;
  bool forces_valid_ = false, energy_valid_ = false;
  ElementCheck last_check_;
};

template <typename T>
CpuEngine<T>::CpuEngine(const formats::Model& model, const Setup& setup, Plan plan)
    : core_(model, setup, std::move(plan)) {
  threads_ = setup.threads > 0 ? setup.threads : omp_get_max_threads();
  a_ = make_engine_arrays<T>(core_.prepared(), kDefaultSlidingSkin);
  n_ = a_.nodes;
  cd_ =
      physics::central_difference<T>(core_.dt(), setup.effects.damping ? setup.damping_alpha : 0.0);
  elem_force_.assign(a_.elements * 8, Vec3<T>{T(0), T(0), T(0)});
  f_.assign(n_, Vec3<T>{T(0), T(0), T(0)});
  activation_.assign(core_.muscle_count(), T(0));
  scalars_.assign(core_.step_scalar_count(), T(0));
  prescribed_free_.resize(a_.constraints.prescribed_set.size());
  sliding_ = HostSlidingState<T>(a_);

  // Initial state: u(0) = 0 with the constraints at t = 0; u(−1) = u(0) − v0 Δt.
  u_.assign(n_, Vec3<T>{T(0), T(0), T(0)});
  un_ = u_;
  apply_constraints(u_, -1, false);
  up_ = u_;
  for (const auto& v : setup.initial_velocities)
    for (auto n : v.nodes)
      for (int k = 0; k < 3; ++k)
        up_[std::size_t(n)][k] = u_[std::size_t(n)][k] - T(v.velocity[std::size_t(k)] * dt());
  for (auto n : core_.prepared().rigid) up_[std::size_t(n)] = u_[std::size_t(n)];
  core_.set_initial_energy(energies());
  forces_valid_ = energy_valid_ = false;
}

template <typename T>
template <bool kElastic, bool kMuscle, bool kHourglass, bool kEnergy>
ElementCheck CpuEngine<T>::element_pass(const std::vector<Index>& elements) {
  std::vector<ElementCheck> partial(chunk_count(elements.size()));
  const ElementData<T> d = a_.element_data();
  for_each_chunk<T>(
      elements.size(), threads_,
      [&](std::size_t c, std::size_t begin, std::size_t end) {
        ElementCheck check;
        for (std::size_t i = begin; i < end; ++i) {
          const std::int32_t e = elements[i];
          const ElementStart<T> s = element_start<T, kMuscle>(d, e, activation_.data());
          Vec3<T> fe[8];
          const T j = element_finish<T, kElastic, kMuscle, kHourglass, kEnergy>(
              d, s, u_.data(), fe, check.strain, check.elastic, check.hourglass);
          check.track(double(j), e);
          Vec3<T>* out = &elem_force_[std::size_t(e) * 8];
          for (int a = 0; a < 8; ++a) out[a] = fe[a];
        }
        partial[c] = check;
      },
      Schedule::balanced);
  ElementCheck total;
  for (const auto& p : partial) total.merge(p);
  return total;
}

template <typename T>
void CpuEngine<T>::compute_forces(bool energy) {
  if (core_.setup().effects.muscles) core_.activations(time(), activation_.data());
  const Effects& fx = core_.setup().effects;
  ElementCheck total;
  for (const auto& c : core_.plan().collections)
    dispatch_flags(
        [&](auto elastic, auto muscle, auto hourglass, auto with_energy) {
          total.merge(
              element_pass<decltype(elastic)::value, decltype(muscle)::value,
                           decltype(hourglass)::value, decltype(with_energy)::value>(c.elements));
        },
        fx.elasticity, c.muscle, fx.hourglass, energy);
  cpu_for_each<T>(n_, threads_, GatherBody<T>{a_.node_data(cd_), elem_force_.data(), f_.data()});
  last_check_ = total;
  forces_valid_ = true;
  energy_valid_ = energy;
}

template <typename T>
template <bool kGravity>
bool CpuEngine<T>::update_nodes() {
  std::vector<char> bad(chunk_count(n_), 0);
  const NodeData<T> d = a_.node_data(cd_);
  for_each_chunk<T>(n_, threads_, [&](std::size_t c, std::size_t begin, std::size_t end) {
    char b = 0;
    for (std::size_t i = begin; i < end; ++i) {
      un_[i] =
          advance_node<T, kGravity>(d, std::int32_t(i), f_[i], u_[i], up_[i], a_.inverse_mass[i]);
      if (!all_finite(un_[i])) b = 1;
    }
    bad[c] = b;
  });
  return std::find(bad.begin(), bad.end(), 1) != bad.end();
}

template <typename T>
double CpuEngine<T>::apply_constraints(std::vector<Vec3<T>>& u, std::int64_t step, bool loads) {
  ConstraintData<T> d = constraint_data();
  d.u_now = u_.data();  // u(n), u(n−1): the lips' contact predicts the partner from them
  d.u_prev = up_.data();
  core_.step_scalars(step, scalars_.data());
  const T* factor = scalars_.data() + core_.muscle_count();
  std::vector<double> partial(chunk_count(std::size_t(d.count)), 0.0);
  // Without sliding a node's ops are a few multiply-adds: a parallel region would cost more.
  const int threads = a_.slide_node.empty() ? 1 : threads_;
  auto run = [&](auto slide) {
    constexpr int kSlide = decltype(slide)::value ? 1 : 0;  // lists refreshed inline
    for_each_chunk<T>(
        std::size_t(d.count), threads, [&](std::size_t c, std::size_t begin, std::size_t end) {
          double w = 0;
          for (std::size_t k = begin; k < end; ++k) {
            const std::int32_t i = d.node[k];
            u[std::size_t(i)] =
                run_program<T, kSlide>(d, i, d.offset[k], d.offset[k + 1], factor, loads,
                                       u[std::size_t(i)], up_.data(), loads, w);
          }
          partial[c] = w;
        });
  };
  dispatch_flags(run, !a_.slide_node.empty());
  double work = 0;
  for (double p : partial) work += p;
  return work;
}

template <typename T>
void CpuEngine<T>::single_step() {
  const bool check_energy = (step_ % core_.setup().energy_interval) == 0;
  ensure_forces(check_energy);
  if (last_check_.element >= 0 && !(last_check_.min_j > 0))
    core_.fail_element(step_, last_check_.element, last_check_.min_j);
  if (check_energy) {
    const double ke = core_.kinetic_energy(u_.data(), up_.data(), a_.inverse_mass.data(), threads_);
    if (core_.blown_up(ke, last_check_.strain + last_check_.hourglass, external_work_)) {
      double move = 0;
      const Index worst = core_.fastest_node(u_.data(), up_.data(), move);
      core_.fail_blowup(step_, ke, external_work_, worst, std::sqrt(move) / dt());
    }
  }

  // Central-difference update of every node (gravity folded in), then loads and constraints.
  const bool gravity = core_.setup().effects.gravity;
  if (gravity ? update_nodes<true>() : update_nodes<false>())
    core_.fail_displacement(step_ + 1, core_.first_non_finite(un_.data()));
  double work = apply_constraints(un_, step_, true);
  if (gravity) {  // work of the weights over this step, centred: g · (u(n+1) − u(n−1)) / 2
    std::vector<double> partial(chunk_count(n_), 0.0);
    for_each_chunk<T>(n_, threads_, [&](std::size_t c, std::size_t begin, std::size_t end) {
      double s = 0;
      for (std::size_t i = begin; i < end; ++i)
        for (int d = 0; d < 3; ++d)
          s += double(a_.gravity[i][d]) * 0.5 * (double(un_[i][d]) - double(up_[i][d]));
      partial[c] = s;
    });
    for (double p : partial) work += p;
  }
  external_work_ += work;

  std::swap(up_, u_);
  std::swap(u_, un_);
  ++step_;
  forces_valid_ = energy_valid_ = false;
}

template <typename T>
Energies CpuEngine<T>::energies() {
  ensure_forces(true);
  Energies e;
  e.step = step_;
  e.time = time();
  e.kinetic = core_.kinetic_energy(u_.data(), up_.data(), a_.inverse_mass.data(), threads_);
  e.strain = last_check_.strain;
  e.elastic = last_check_.elastic;
  e.hourglass = last_check_.hourglass;
  e.external_work = external_work_;
  return e;
}

template <typename T>
State CpuEngine<T>::state() const {
  return core_.make_state(step_, u_, up_, sliding_.triangle, external_work_);
}

template <typename T>
void CpuEngine<T>::restore(const State& s) {
  core_.check_state(s);
  u_ = unflatten<T>(s.u);
  up_ = unflatten<T>(s.u_prev);
  sliding_.restore(s.sliding_triangle);
  step_ = s.step;
  external_work_ = s.external_work;
  core_.set_energy_reference(s.energy_reference);
  forces_valid_ = energy_valid_ = false;
}

}  // namespace

std::unique_ptr<Backend> make_cpu_backend(const formats::Model& model, const Setup& setup) {
  Plan plan = make_plan(model, setup);
  for (const auto& w : plan.warnings) log::warn("{}", w);
  if (setup.precision == Precision::float32)
    return std::make_unique<CpuEngine<float>>(model, setup, std::move(plan));
  return std::make_unique<CpuEngine<double>>(model, setup, std::move(plan));
}

}  // namespace sinew::simulator
