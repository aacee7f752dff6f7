#include "sinew/partition/partitioned_engine.hpp"

#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

#include "sinew/common/error.hpp"
#include "sinew/common/log.hpp"
#include "sinew/partition/partition.hpp"
#include "sinew/simulator/engine/backend_core.hpp"
#include "sinew/simulator/passes/constraint_program.hpp"
#include "sinew/simulator/passes/cpu_for_each.hpp"
#include "sinew/simulator/passes/effect_dispatch.hpp"
#include "sinew/simulator/passes/element_pass.hpp"
#include "sinew/simulator/passes/node_pass.hpp"

namespace sinew::partition {
namespace {

using simulator::BackendCore;
using simulator::Energies;
using simulator::EngineArrays;
using simulator::Frame;
using simulator::kChunk;
using simulator::Plan;
using simulator::State;

template <typename T>
MPI_Datatype mpi_scalar() {
  return std::is_same_v<T, float> ? MPI_FLOAT : MPI_DOUBLE;
}

void check_mpi(int rc, const char* what) {
  if (rc != MPI_SUCCESS) throw IoError("", what, fmt::format("MPI error code {}", rc));
}

// The smallest J over a rank's primary elements, in the one-device order (collection, position):
// the first NaN wins, else the smallest J, ties to the earlier position (the CPU engine's
// ElementCheck::track). `key` orders the ranks' results when they are merged.
struct JacobianCheck {
  double min_j = std::numeric_limits<double>::infinity();
  std::int64_t element = -1;
  std::int64_t key = 0;
  void track(double j, std::int64_t e, std::int64_t k) {
    if (element < 0 || (!std::isnan(min_j) && (std::isnan(j) || j < min_j))) {
      min_j = j;
      element = e;
      key = k;
    }
  }
};

// What every step checks, one all-gather for both: the smallest J at u(n) and the first node whose
// u(n+1) is not finite (INT_MAX: none).
struct StepCheck {
  JacobianCheck jacobian;
  std::int64_t first_bad = INT_MAX;
};

// The scalars of constraint entry k's work record (constraint_work): u(n+1), u(n−1) and the
// projections' moves, then u* of each of its prescribed sets (and of its jaw move).
template <typename T>
int record_size(const simulator::ConstraintArrays<T>& c, std::size_t k) {
  int size = 9;
  for (std::int32_t q = c.offset[k]; q < c.offset[k + 1]; ++q)
    if (simulator::op_prescribes(c.op[std::size_t(q)])) size += 3;
  return size;
}

template <typename T>
class PartitionedCpuEngine final : public simulator::Backend {
 public:
  PartitionedCpuEngine(const formats::Model& model, const simulator::Setup& setup, Plan plan,
                       MPI_Comm comm);

  std::string name() const override { return fmt::format("cpu-mpi ({} parts)", size_); }
  const Plan& plan() const override { return core_.plan(); }
  void step(std::int64_t n) override {
    for (std::int64_t k = 0; k < n; ++k) single_step();
  }
  std::int64_t step_index() const override { return step_; }
  double time() const override { return core_.time(step_); }
  double dt() const override { return core_.dt(); }
  State state() const override {
    return core_.make_state(step_, whole(u_), whole(up_), sliding_triangles(), external_work_);
  }
  void restore(const State& s) override {
    core_.check_state(s);
    u_ = simulator::unflatten<T>(s.u);
    up_ = simulator::unflatten<T>(s.u_prev);
    sliding_.restore(s.sliding_triangle);
    step_ = s.step;
    external_work_ = s.external_work;
    core_.set_energy_reference(s.energy_reference);
  }
  std::vector<double> displacements() const override {
    const auto u = whole(u_);
    return simulator::flatten(u.data(), n_);
  }
  std::vector<double> displacements(const std::vector<Index>& nodes) const override {
    core_.check_node_ids(nodes, "nodes");
    const auto u = whole(u_);
    std::vector<Vec3<T>> picked;
    for (auto v : nodes) picked.push_back(u[std::size_t(v)]);
    return simulator::flatten(picked.data(), picked.size());
  }
  std::vector<double> velocities() const override {
    return core_.velocities(whole(u_).data(), whole(up_).data());
  }
  std::vector<double> internal_forces() override {
    const auto f = forces_now();
    return simulator::flatten(f.data(), n_);
  }
  std::array<double, 3> reaction(const std::vector<Index>& nodes) override {
    const auto f = forces_now();
    core_.check_node_ids(nodes, "reaction");
    std::vector<Vec3<T>> set_forces;
    for (auto v : nodes) set_forces.push_back(f[std::size_t(v)]);
    return core_.reaction(a_, nodes, set_forces.data(), step_);
  }
  Energies energies() override { return energies_at(whole(u_), whole(up_)); }
  simulator::ElementFields element_fields() override {
    return core_.element_fields(a_, whole(u_).data(), step_, threads_);
  }
  Frame frame(bool with_fields) override {
    Frame f{step_, time(), displacements(), energies(), {}};
    if (with_fields) f.fields = core_.deferred_element_fields(a_, whole(u_), step_, threads_);
    return f;
  }
  // Steering (sinew-live) is for one device: a partitioned run follows its scene's curves.
  void set_activation_override(std::size_t, std::optional<double>) override {
    throw ConfigError("", "steering",
                      "a partitioned run cannot be steered (sinew-live runs on one device)");
  }
  std::optional<double> activation_override(std::size_t) const override { return std::nullopt; }
  std::size_t force_slot_count() const override { return 0; }
  void set_force_slot(std::size_t, const std::vector<Index>&,
                      const std::array<double, 3>&) override {
    throw ConfigError("", "steering", "a partitioned run has no live force slots");
  }
  void clear_force_slot(std::size_t) override {
    throw ConfigError("", "steering", "a partitioned run has no live force slots");
  }

 private:
  // Every binding's closest triangle, from its owner.
  std::vector<Index> sliding_triangles() const;
  // v with every node's value from its owner (the owned values of every rank gathered).
  std::vector<Vec3<T>> whole(const std::vector<Vec3<T>>& v) const;
  // The element forces of this part's elements at u(n) (J of each into jacobian_).
  void element_forces(const std::vector<std::vector<Index>>& lists);
  template <bool kElastic, bool kMuscle, bool kHourglass>
  void element_list(const std::vector<Index>& list);
  // Gather, update, loads and constraints of the listed owned nodes into un_ (the projections'
  // moves of constrained nodes into projected_); the lowest node whose update is not finite into
  // `bad`.
  void update_nodes(const std::vector<Index>& list, const T* factor, Index& bad);
  simulator::ConstraintData<T> constraint_data() {
    return simulator::host_constraint_data(a_, cd_, prescribed_free_.data(), sliding_);
  }
  // The external work over this step in the CPU engine's order: every constrained node's terms
  // (add_program_work) on every rank from its owner's record, chunk by chunk of constrained
  // nodes; then the weights' work from every node's terms, gathered.
  double constraint_work(const T* factor);
  // The step's checks merged over the ranks; `bad`: this rank's first non-finite node.
  StepCheck step_check(Index bad);
  Energies energies_at(const std::vector<Vec3<T>>& u, const std::vector<Vec3<T>>& up);
  std::vector<Vec3<T>> forces_now();
  void single_step();

  BackendCore core_;
  EngineArrays<T> a_;
  MPI_Comm comm_;
  int rank_ = 0, size_ = 1, threads_ = 1;
  std::size_t n_ = 0;
  Partition partition_;
  simulator::physics::CentralDifference<T> cd_;
  // Per plan collection: this part's elements next to nodes other parts need (boundary) and the
  // rest (interior), in collection order.
  std::vector<std::vector<Index>> boundary_elements_, interior_elements_;
  std::vector<Index> boundary_nodes_, interior_nodes_;  // owned: sent to a neighbour, or not
  std::vector<double> jacobian_;                        // E, J of the computed elements
  std::vector<std::int32_t> entry_of_node_;             // N, constraint entry of a node or −1
  // The constraint entries per owner part (in entry order), and the scalars of their work records
  // per part (constraint_work: u(n+1), u(n−1), the projections' moves, u* of each prescribed set).
  std::vector<std::vector<std::int32_t>> entries_of_part_;
  std::vector<int> record_counts_, record_displs_;
  std::vector<std::size_t> record_at_;    // C, where entry k's record starts in records_
  std::vector<T> records_;                // every entry's record, gathered by part
  std::vector<std::size_t> gathered_at_;  // N, node i's first scalar in an owned-values gather
  std::vector<double> gravity_terms_;     // every node's 3 weight work terms, gathered by part
  // Sliding: the CPU engine's state per binding, kept up to date by the binding's owner only; the
  // surfaces (read-only) on every rank.
  simulator::HostSlidingState<T> sliding_;
  std::vector<int> binding_counts_, binding_displs_;  // per part, for state()
  std::vector<std::int32_t> bindings_by_owner_;       // binding ids, part by part
  std::vector<int> owned_counts_, owned_displs_;      // scalars per part (3 per owned node)
  std::vector<T> activation_, scalars_;
  std::vector<Vec3<T>> elem_force_, f_, prescribed_free_;
  std::vector<Vec3<T>> projected_;  // C, per constraint entry: its projections' moves this step
  std::vector<std::vector<T>> send_buf_, recv_buf_;
  std::vector<Vec3<T>> u_, up_, un_;
  std::int64_t step_ = 0;
  double external_work_ = 0;
};

template <typename T>
PartitionedCpuEngine<T>::PartitionedCpuEngine(const formats::Model& model,
                                              const simulator::Setup& setup, Plan plan,
                                              MPI_Comm comm)
    : core_(model, setup, plan), comm_(comm) {
  // The lips' contact reads its partner's u(n), which may lie outside this rank's halo.
  if (setup.lip_contact)
    throw ConfigError("", "effects",
                      "'contact' (the lips' contact) is not in the partitioned engine yet: run the "
                      "scene on one process (sinew-simulate) or leave contact out");
  MPI_Comm_rank(comm_, &rank_);
  MPI_Comm_size(comm_, &size_);
  threads_ = setup.threads > 0 ? setup.threads : omp_get_max_threads();
  a_ = simulator::make_engine_arrays<T>(core_.prepared(), simulator::kDefaultSlidingSkin);
  n_ = a_.nodes;
  partition_ = make_partition(model, work_of(model, plan), size_);
  const Part& part = partition_.parts[std::size_t(rank_)];
  cd_ = simulator::physics::central_difference<T>(
      core_.dt(), setup.effects.damping ? setup.damping_alpha : 0.0);

  std::vector<char> boundary(n_, 0), touches_boundary(model.element_count(), 0);
  for (const auto& s : part.sends)
    for (Index v : s.nodes) boundary[std::size_t(v)] = 1;
  for (Index v : part.owned_nodes)
    (boundary[std::size_t(v)] ? boundary_nodes_ : interior_nodes_).push_back(v);
  std::vector<char> computed(model.element_count(), 0);
  for (Index e : part.elements) {
    computed[std::size_t(e)] = 1;
    for (Index v : model.element_nodes[std::size_t(e)])
      if (boundary[std::size_t(v)]) touches_boundary[std::size_t(e)] = 1;
  }
  for (const auto& c : core_.plan().collections) {
    boundary_elements_.emplace_back();
    interior_elements_.emplace_back();
    for (Index e : c.elements)
      if (computed[std::size_t(e)])
        (touches_boundary[std::size_t(e)] ? boundary_elements_ : interior_elements_)
            .back()
            .push_back(e);
  }
  for (const auto& r : part.receives) recv_buf_.emplace_back(3 * r.nodes.size());
  for (const auto& s : part.sends) send_buf_.emplace_back(3 * s.nodes.size());
  for (const auto& p : partition_.parts) {
    owned_displs_.push_back(owned_counts_.empty() ? 0
                                                  : owned_displs_.back() + owned_counts_.back());
    owned_counts_.push_back(int(3 * p.owned_nodes.size()));
  }
  const auto& c = a_.constraints;
  entry_of_node_.assign(n_, -1);
  entries_of_part_.resize(std::size_t(size_));
  record_counts_.assign(std::size_t(size_), 0);
  for (std::size_t k = 0; k < c.node.size(); ++k) {
    entry_of_node_[std::size_t(c.node[k])] = std::int32_t(k);
    const int p = partition_.node_owner[std::size_t(c.node[k])];
    entries_of_part_[std::size_t(p)].push_back(std::int32_t(k));
    record_counts_[std::size_t(p)] += record_size(c, k);
  }
  record_at_.resize(c.node.size());
  for (int p = 0; p < size_; ++p) {
    record_displs_.push_back(p == 0 ? 0
                                    : record_displs_.back() + record_counts_[std::size_t(p - 1)]);
    std::size_t at = std::size_t(record_displs_.back());
    for (std::int32_t k : entries_of_part_[std::size_t(p)]) {
      record_at_[std::size_t(k)] = at;
      at += std::size_t(record_size(c, std::size_t(k)));
    }
  }
  records_.resize(std::size_t(record_displs_.back() + record_counts_.back()));
  projected_.assign(c.node.size(), Vec3<T>{T(0), T(0), T(0)});
  gathered_at_.resize(n_);
  for (const auto& p : partition_.parts)
    for (std::size_t k = 0; k < p.owned_nodes.size(); ++k)
      gathered_at_[std::size_t(p.owned_nodes[k])] =
          std::size_t(owned_displs_[std::size_t(p.index)]) + 3 * k;
  if (setup.effects.gravity) gravity_terms_.resize(3 * n_);
  sliding_ = simulator::HostSlidingState<T>(a_);
  const std::size_t slides = a_.slide_node.size();
  for (int p = 0; p < size_; ++p) {
    binding_displs_.push_back(int(bindings_by_owner_.size()));
    for (std::size_t k = 0; k < slides; ++k)
      if (partition_.node_owner[std::size_t(a_.slide_node[k])] == p)
        bindings_by_owner_.push_back(std::int32_t(k));
    binding_counts_.push_back(int(bindings_by_owner_.size()) - binding_displs_.back());
  }

  jacobian_.assign(model.element_count(), 0.0);
  elem_force_.assign(a_.elements * 8, Vec3<T>{T(0), T(0), T(0)});
  f_.assign(n_, Vec3<T>{T(0), T(0), T(0)});
  activation_.assign(core_.muscle_count(), T(0));
  scalars_.assign(core_.step_scalar_count(), T(0));
  prescribed_free_.resize(c.prescribed_set.size());

  // Initial state, as the CPU engine on every rank (all nodes): u(0) = 0 with the constraints at
  // t = 0 (no loads, no work); u(−1) = u(0) − v0 Δt.
  u_.assign(n_, Vec3<T>{T(0), T(0), T(0)});
  un_ = u_;
  {
    simulator::DenormalGuard<T> guard;  // T's floating-point mode, as the CPU engine's chunks
    const auto d = constraint_data();
    core_.step_scalars(-1, scalars_.data());
    const T* factor = scalars_.data() + core_.muscle_count();
    double w = 0;
    simulator::dispatch_flags(
        [&](auto slide) {
          constexpr int kSlide = decltype(slide)::value ? 1 : 0;
          for (std::int32_t k = 0; k < d.count; ++k) {
            const std::int32_t i = d.node[k];
            u_[std::size_t(i)] =
                simulator::run_program<T, kSlide>(d, i, d.offset[k], d.offset[k + 1], factor, false,
                                                  u_[std::size_t(i)], up_.data(), false, w);
          }
        },
        !a_.slide_node.empty());
  }
  up_ = u_;
  for (const auto& v : setup.initial_velocities)
    for (auto n : v.nodes)
      for (int k = 0; k < 3; ++k)
        up_[std::size_t(n)][k] = u_[std::size_t(n)][k] - T(v.velocity[std::size_t(k)] * dt());
  for (auto n : core_.prepared().rigid) up_[std::size_t(n)] = u_[std::size_t(n)];
  core_.set_initial_energy(energies());
}

template <typename T>
std::vector<Vec3<T>> PartitionedCpuEngine<T>::whole(const std::vector<Vec3<T>>& v) const {
  const Part& part = partition_.parts[std::size_t(rank_)];
  std::vector<T> mine(3 * part.owned_nodes.size());
  for (std::size_t k = 0; k < part.owned_nodes.size(); ++k)
    for (int c = 0; c < 3; ++c)
      mine[3 * k + std::size_t(c)] = v[std::size_t(part.owned_nodes[k])][c];
  std::vector<T> all(3 * n_);
  check_mpi(MPI_Allgatherv(mine.data(), int(mine.size()), mpi_scalar<T>(), all.data(),
                           owned_counts_.data(), owned_displs_.data(), mpi_scalar<T>(), comm_),
            "MPI_Allgatherv (owned nodes)");
  std::vector<Vec3<T>> out(n_);
  for (const auto& p : partition_.parts) {
    const T* from = all.data() + owned_displs_[std::size_t(p.index)];
    for (std::size_t k = 0; k < p.owned_nodes.size(); ++k)
      out[std::size_t(p.owned_nodes[k])] = {from[3 * k], from[3 * k + 1], from[3 * k + 2]};
  }
  return out;
}

template <typename T>
std::vector<Index> PartitionedCpuEngine<T>::sliding_triangles() const {
  const int first = binding_displs_[std::size_t(rank_)];
  std::vector<std::int32_t> mine;
  for (int j = 0; j < binding_counts_[std::size_t(rank_)]; ++j)
    mine.push_back(sliding_.triangle[std::size_t(bindings_by_owner_[std::size_t(first + j)])]);
  std::vector<std::int32_t> all(bindings_by_owner_.size());
  check_mpi(MPI_Allgatherv(mine.data(), int(mine.size()), MPI_INT32_T, all.data(),
                           binding_counts_.data(), binding_displs_.data(), MPI_INT32_T, comm_),
            "MPI_Allgatherv (sliding triangles)");
  std::vector<Index> out(bindings_by_owner_.size());
  for (std::size_t j = 0; j < all.size(); ++j) out[std::size_t(bindings_by_owner_[j])] = all[j];
  return out;
}

template <typename T>
template <bool kElastic, bool kMuscle, bool kHourglass>
void PartitionedCpuEngine<T>::element_list(const std::vector<Index>& list) {
  const simulator::ElementData<T> d = a_.element_data();
  simulator::for_each_chunk<T>(
      list.size(), threads_,
      [&](std::size_t, std::size_t begin, std::size_t end) {
        double strain = 0, elastic = 0, hourglass = 0;  // kEnergy off: untouched
        for (std::size_t i = begin; i < end; ++i) {
          const std::int32_t e = list[i];
          const auto s = simulator::element_start<T, kMuscle>(d, e, activation_.data());
          Vec3<T> fe[8];
          const T j = simulator::element_finish<T, kElastic, kMuscle, kHourglass, false>(
              d, s, u_.data(), fe, strain, elastic, hourglass);
          jacobian_[std::size_t(e)] = double(j);
          Vec3<T>* out = &elem_force_[std::size_t(e) * 8];
          for (int a = 0; a < 8; ++a) out[a] = fe[a];
        }
      },
      simulator::Schedule::balanced);
}

template <typename T>
void PartitionedCpuEngine<T>::element_forces(const std::vector<std::vector<Index>>& lists) {
  const auto& fx = core_.setup().effects;
  const auto& collections = core_.plan().collections;
  for (std::size_t k = 0; k < collections.size(); ++k)
    simulator::dispatch_flags(
        [&](auto elastic, auto muscle, auto hourglass) {
          element_list<decltype(elastic)::value, decltype(muscle)::value,
                       decltype(hourglass)::value>(lists[k]);
        },
        fx.elasticity, collections[k].muscle, fx.hourglass);
}

template <typename T>
void PartitionedCpuEngine<T>::update_nodes(const std::vector<Index>& list, const T* factor,
                                           Index& bad) {
  const simulator::NodeData<T> d = a_.node_data(cd_);
  const simulator::ConstraintData<T> cdata = constraint_data();
  std::vector<Index> first_bad(simulator::chunk_count(list.size()), INT_MAX);
  simulator::dispatch_flags(
      [&](auto gravity, auto slide) {
        constexpr bool kGravity = decltype(gravity)::value;
        constexpr int kSlide = decltype(slide)::value ? 1 : 0;  // lists refreshed inline
        simulator::for_each_chunk<T>(
            list.size(), threads_, [&](std::size_t c, std::size_t begin, std::size_t end) {
              for (std::size_t k = begin; k < end; ++k) {
                const std::int32_t i = list[k];
                const std::size_t ii = std::size_t(i);
                const Vec3<T> f = simulator::node_internal_force(d, elem_force_.data(), i);
                f_[ii] = f;
                Vec3<T> v = simulator::advance_node<T, kGravity>(d, i, f, u_[ii], up_[ii],
                                                                 a_.inverse_mass[ii]);
                if (!simulator::all_finite(v)) first_bad[c] = std::min(first_bad[c], Index(i));
                const std::int32_t entry = entry_of_node_[ii];
                if (entry >= 0) {
                  // Its work is added by constraint_work, on every rank in the one-device order.
                  Vec3<T>& projected = projected_[std::size_t(entry)];
                  projected = Vec3<T>{T(0), T(0), T(0)};
                  v = simulator::run_ops<T, kSlide>(cdata, i, cdata.offset[entry],
                                                    cdata.offset[entry + 1], factor, true, v,
                                                    projected);
                }
                un_[ii] = v;
              }
            });
      },
      core_.setup().effects.gravity, !a_.slide_node.empty());
  for (Index b : first_bad) bad = std::min(bad, b);
}

template <typename T>
double PartitionedCpuEngine<T>::constraint_work(const T* factor) {
  // The CPU engine sums both works inside for_each_chunk, in scalar T's floating-point mode (in
  // float, denormals flushed: they would change a term's bits).
  simulator::DenormalGuard<T> guard;
  const simulator::ConstraintData<T> d = constraint_data();
  double work = 0;
  if (d.count > 0) {
    // Every entry's record from its owner (what add_program_work reads of it), this rank's written
    // in place into the gathered buffer.
    for (std::int32_t k : entries_of_part_[std::size_t(rank_)]) {
      T* to = records_.data() + record_at_[std::size_t(k)];
      auto put = [&](const Vec3<T>& x) {
        for (int c = 0; c < 3; ++c) *to++ = x[c];
      };
      const std::size_t i = std::size_t(d.node[k]);
      put(un_[i]);
      put(up_[i]);
      put(projected_[std::size_t(k)]);
      for (std::int32_t q = d.offset[k]; q < d.offset[k + 1]; ++q)
        if (simulator::op_prescribes(d.op[q]))
          put(prescribed_free_[std::size_t(d.op[q] & simulator::kOpArg)]);
    }
    check_mpi(MPI_Allgatherv(MPI_IN_PLACE, 0, MPI_DATATYPE_NULL, records_.data(),
                             record_counts_.data(), record_displs_.data(), mpi_scalar<T>(), comm_),
              "MPI_Allgatherv (constraint work)");
    // The CPU engine's apply_constraints sums: term by term within a chunk of 1024 entries, then
    // the chunks in order. u* of a prescribed set goes into prescribed_free_ (the owner's value;
    // this rank's own entries get theirs back), where add_program_work reads it.
    std::vector<double> partial(simulator::chunk_count(std::size_t(d.count)), 0.0);
    for (std::size_t c = 0; c < partial.size(); ++c) {
      double w = 0;
      const std::size_t end = std::min(std::size_t(d.count), (c + 1) * kChunk);
      for (std::size_t k = c * kChunk; k < end; ++k) {
        if (d.offset[k] == d.offset[k + 1]) continue;
        const T* from = records_.data() + record_at_[k];
        auto get = [&] {
          const Vec3<T> x{from[0], from[1], from[2]};
          from += 3;
          return x;
        };
        const Vec3<T> v = get(), vp = get(), projected = get();
        for (std::int32_t q = d.offset[k]; q < d.offset[k + 1]; ++q)
          if (simulator::op_prescribes(d.op[q]))
            prescribed_free_[std::size_t(d.op[q] & simulator::kOpArg)] = get();
        simulator::add_program_work(d, d.node[k], d.offset[k], d.offset[k + 1], factor, v, vp,
                                    projected, w);
      }
      partial[c] = w;
    }
    for (double p : partial) work += p;
  }
  if (core_.setup().effects.gravity) {
    // The weights' work, centred: g · (u(n+1) − u(n−1)) / 2, per node, summed per chunk of 1024
    // nodes in id order as the CPU engine sums it: every node's three terms from its owner.
    const Part& part = partition_.parts[std::size_t(rank_)];
    double* mine = gravity_terms_.data() + owned_displs_[std::size_t(rank_)];
    for (std::size_t k = 0; k < part.owned_nodes.size(); ++k) {
      const std::size_t i = std::size_t(part.owned_nodes[k]);
      for (int c = 0; c < 3; ++c)
        mine[3 * k + std::size_t(c)] =
            double(a_.gravity[i][c]) * 0.5 * (double(un_[i][c]) - double(up_[i][c]));
    }
    check_mpi(MPI_Allgatherv(MPI_IN_PLACE, 0, MPI_DATATYPE_NULL, gravity_terms_.data(),
                             owned_counts_.data(), owned_displs_.data(), MPI_DOUBLE, comm_),
              "MPI_Allgatherv (gravity work)");
    std::vector<double> partial(simulator::chunk_count(n_), 0.0);
    for (std::size_t c = 0; c < partial.size(); ++c) {
      double s = 0;
      for (std::size_t i = c * kChunk; i < std::min(n_, (c + 1) * kChunk); ++i) {
        const double* t = gravity_terms_.data() + gathered_at_[i];
        for (std::size_t k = 0; k < 3; ++k) s += t[k];
      }
      partial[c] = s;
    }
    for (double p : partial) work += p;
  }
  return work;
}

template <typename T>
StepCheck PartitionedCpuEngine<T>::step_check(Index bad) {
  StepCheck check;
  check.first_bad = bad;
  JacobianCheck& mine = check.jacobian;
  const auto& collections = core_.plan().collections;
  for (std::size_t k = 0; k < collections.size(); ++k) {
    const auto& list = collections[k].elements;
    for (std::size_t pos = 0; pos < list.size(); ++pos) {
      const std::size_t e = std::size_t(list[pos]);
      if (partition_.element_primary[e] == rank_)
        mine.track(jacobian_[e], std::int64_t(e), (std::int64_t(k) << 40) + std::int64_t(pos));
    }
  }
  std::vector<StepCheck> all(static_cast<std::size_t>(size_));
  check_mpi(MPI_Allgather(&check, sizeof(StepCheck), MPI_BYTE, all.data(), sizeof(StepCheck),
                          MPI_BYTE, comm_),
            "MPI_Allgather (step checks)");
  std::sort(all.begin(), all.end(),
            [](const StepCheck& a, const StepCheck& b) { return a.jacobian.key < b.jacobian.key; });
  StepCheck total;
  for (const auto& o : all) {
    if (o.jacobian.element >= 0)
      total.jacobian.track(o.jacobian.min_j, o.jacobian.element, o.jacobian.key);
    total.first_bad = std::min(total.first_bad, o.first_bad);
  }
  return total;
}

template <typename T>
Energies PartitionedCpuEngine<T>::energies_at(const std::vector<Vec3<T>>& u,
                                              const std::vector<Vec3<T>>& up) {
  if (core_.setup().effects.muscles) core_.activations(time(), activation_.data());
  // The one-device chunks of each collection, dealt to the ranks in turn.
  const auto& collections = core_.plan().collections;
  std::vector<std::pair<std::size_t, std::size_t>> chunks;  // (collection, chunk)
  for (std::size_t k = 0; k < collections.size(); ++k)
    for (std::size_t c = 0; c < simulator::chunk_count(collections[k].elements.size()); ++c)
      chunks.emplace_back(k, c);
  const std::size_t per = (chunks.size() + std::size_t(size_) - 1) / std::size_t(size_);
  // Three sums per chunk: strain, elastic, hourglass.
  std::vector<double> mine(3 * per, 0.0), all(3 * per * std::size_t(size_), 0.0);
  const simulator::ElementData<T> d = a_.element_data();
  const auto& fx = core_.setup().effects;
  for (std::size_t j = 0; j < per; ++j) {
    const std::size_t g = std::size_t(rank_) + j * std::size_t(size_);
    if (g >= chunks.size()) break;
    const auto& list = collections[chunks[g].first].elements;
    const std::size_t begin = chunks[g].second * kChunk,
                      end = std::min(list.size(), begin + kChunk);
    double strain = 0, elastic_energy = 0, hourglass = 0;
    simulator::dispatch_flags(
        [&](auto elastic, auto muscle, auto hg) {
          constexpr bool kMuscle = decltype(muscle)::value;
          simulator::DenormalGuard<T> guard;
          for (std::size_t i = begin; i < end; ++i) {
            const auto s = simulator::element_start<T, kMuscle>(d, list[i], activation_.data());
            Vec3<T> fe[8];
            simulator::element_finish<T, decltype(elastic)::value, kMuscle, decltype(hg)::value,
                                      true>(d, s, u.data(), fe, strain, elastic_energy, hourglass);
          }
        },
        fx.elasticity, collections[chunks[g].first].muscle, fx.hourglass);
    mine[3 * j] = strain;
    mine[3 * j + 1] = elastic_energy;
    mine[3 * j + 2] = hourglass;
  }
  check_mpi(MPI_Allgather(mine.data(), int(mine.size()), MPI_DOUBLE, all.data(), int(mine.size()),
                          MPI_DOUBLE, comm_),
            "MPI_Allgather (energy chunks)");
  // Added as the CPU engine adds them: chunks in order within a collection, then collections.
  double strain = 0, elastic = 0, hourglass = 0;
  std::size_t g = 0;
  for (std::size_t k = 0; k < collections.size(); ++k) {
    double cs = 0, ce = 0, ch = 0;
    for (std::size_t c = 0; c < simulator::chunk_count(collections[k].elements.size()); ++c, ++g) {
      const std::size_t at = 3 * ((g % std::size_t(size_)) * per + g / std::size_t(size_));
      cs += all[at];
      ce += all[at + 1];
      ch += all[at + 2];
    }
    strain += cs;
    elastic += ce;
    hourglass += ch;
  }
  Energies e;
  e.step = step_;
  e.time = time();
  e.kinetic = core_.kinetic_energy(u.data(), up.data(), a_.inverse_mass.data(), threads_);
  e.strain = strain;
  e.elastic = elastic;
  e.hourglass = hourglass;
  e.external_work = external_work_;
  return e;
}

template <typename T>
std::vector<Vec3<T>> PartitionedCpuEngine<T>::forces_now() {
  if (core_.setup().effects.muscles) core_.activations(time(), activation_.data());
  element_forces(boundary_elements_);
  element_forces(interior_elements_);
  const simulator::NodeData<T> d = a_.node_data(cd_);
  simulator::DenormalGuard<T> guard;  // T's floating-point mode, as the CPU engine's gather
  for (Index i : partition_.parts[std::size_t(rank_)].owned_nodes)
    f_[std::size_t(i)] = simulator::node_internal_force(d, elem_force_.data(), i);
  return whole(f_);
}

template <typename T>
void PartitionedCpuEngine<T>::single_step() {
  const bool check_energy = (step_ % core_.setup().energy_interval) == 0;
  if (core_.setup().effects.muscles) core_.activations(time(), activation_.data());
  core_.step_scalars(step_, scalars_.data());
  const T* factor = scalars_.data() + core_.muscle_count();
  const Part& part = partition_.parts[std::size_t(rank_)];

  // 1. What the neighbours need first, then sent while 2. the interior is computed.
  Index bad = INT_MAX;
  element_forces(boundary_elements_);
  update_nodes(boundary_nodes_, factor, bad);
  std::vector<MPI_Request> requests;
  for (std::size_t r = 0; r < part.receives.size(); ++r) {
    requests.emplace_back();
    check_mpi(MPI_Irecv(recv_buf_[r].data(), int(recv_buf_[r].size()), mpi_scalar<T>(),
                        part.receives[r].part, 0, comm_, &requests.back()),
              "MPI_Irecv (halo)");
  }
  for (std::size_t s = 0; s < part.sends.size(); ++s) {
    const auto& nodes = part.sends[s].nodes;
    for (std::size_t k = 0; k < nodes.size(); ++k)
      for (int c = 0; c < 3; ++c)
        send_buf_[s][3 * k + std::size_t(c)] = un_[std::size_t(nodes[k])][c];
    requests.emplace_back();
    check_mpi(MPI_Isend(send_buf_[s].data(), int(send_buf_[s].size()), mpi_scalar<T>(),
                        part.sends[s].part, 0, comm_, &requests.back()),
              "MPI_Isend (halo)");
  }
  element_forces(interior_elements_);
  update_nodes(interior_nodes_, factor, bad);
  // 3. The halo's u(n+1).
  check_mpi(MPI_Waitall(int(requests.size()), requests.data(), MPI_STATUSES_IGNORE),
            "MPI_Waitall (halo)");
  for (std::size_t r = 0; r < part.receives.size(); ++r) {
    const auto& nodes = part.receives[r].nodes;
    for (std::size_t k = 0; k < nodes.size(); ++k)
      un_[std::size_t(nodes[k])] = {recv_buf_[r][3 * k], recv_buf_[r][3 * k + 1],
                                    recv_buf_[r][3 * k + 2]};
  }

  // The one-device checks in its order, on the state u(n) (nothing is swapped yet).
  const StepCheck checks = step_check(bad);
  const JacobianCheck& j = checks.jacobian;
  if (j.element >= 0 && !(j.min_j > 0)) core_.fail_element(step_, Index(j.element), j.min_j);
  if (check_energy) {
    const auto u = whole(u_), up = whole(up_);
    const Energies e = energies_at(u, up);
    if (core_.blown_up(e.kinetic, e.strain + e.hourglass, external_work_)) {
      double move = 0;
      const Index worst = core_.fastest_node(u.data(), up.data(), move);
      core_.fail_blowup(step_, e.kinetic, external_work_, worst, std::sqrt(move) / dt());
    }
  }
  if (checks.first_bad != INT_MAX) core_.fail_displacement(step_ + 1, Index(checks.first_bad));
  external_work_ += constraint_work(factor);

  std::swap(up_, u_);
  std::swap(u_, un_);
  ++step_;
}

}  // namespace

std::unique_ptr<simulator::Backend> make_partitioned_cpu_backend(const formats::Model& model,
                                                                 const simulator::Setup& setup,
                                                                 MPI_Comm comm) {
  Plan plan = simulator::make_plan(model, setup);
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  if (rank == 0)
    for (const auto& w : plan.warnings) log::warn("{}", w);
  if (setup.precision == simulator::Precision::float32)
    return std::make_unique<PartitionedCpuEngine<float>>(model, setup, std::move(plan), comm);
  return std::make_unique<PartitionedCpuEngine<double>>(model, setup, std::move(plan), comm);
}

}  // namespace sinew::partition
