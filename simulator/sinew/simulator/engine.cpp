#include "sinew/simulator/engine.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>
#if defined(__x86_64__) || defined(__SSE2__)
#include <xmmintrin.h>
#define SINEW_HAVE_MXCSR 1
#endif

#include <fmt/format.h>

#include "sinew/common/error.hpp"
#include "sinew/common/log.hpp"
#include "sinew/common/math.hpp"
#include "sinew/simulator/physics/central_difference.hpp"
#include "sinew/simulator/physics/element.hpp"
#include "sinew/simulator/physics/hex8.hpp"
#include "sinew/simulator/physics/muscle.hpp"
#include "sinew/simulator/physics/sliding.hpp"
#include "sinew/simulator/prepared_model.hpp"
#include "sinew/simulator/sliding_grid.hpp"

namespace sinew::simulator {
namespace {

// Reductions (energies, checks) are summed per fixed chunk and then chunk by chunk in order, so
// they do not depend on the thread count either.
constexpr std::size_t kChunk = 1024;
// Below this many items a loop runs on the calling thread: a parallel region costs more than it
// saves, and spinning threads hurt on a shared machine. Results are identical either way.
constexpr std::size_t kParallelMin = 2 * kChunk;

inline std::size_t chunk_count(std::size_t n) {
  return (n + kChunk - 1) / kChunk;
}

// Float runs flush subnormals to zero (FTZ + DAZ) inside the engine's loops: displacements far
// from the loads start tiny and underflow into subnormals, which cost some CPUs 2× in float
// (measured on the GPU machine's CPU). Every thread uses the same mode, so results stay independent
// of the thread count; the caller's mode is restored at the end of each chunk. Double never gets
// there.
template <typename T>
struct DenormalGuard {
#ifdef SINEW_HAVE_MXCSR
  unsigned saved = 0;
  DenormalGuard() {
    if constexpr (std::is_same_v<T, float>) {
      saved = _mm_getcsr();
      _mm_setcsr(saved | 0x8040u);  // FTZ (bit 15) | DAZ (bit 6)
    }
  }
  ~DenormalGuard() {
    if constexpr (std::is_same_v<T, float>) _mm_setcsr(saved);
  }
  DenormalGuard(const DenormalGuard&) = delete;
  DenormalGuard& operator=(const DenormalGuard&) = delete;
#endif
};

struct ElementCheck {
  double min_j = std::numeric_limits<double>::infinity();
  Index element = -1;
  double strain = 0, hourglass = 0;
  void merge(const ElementCheck& o) {
    // NaN counts as the worst; ties keep the lower element id (chunks are merged in order).
    const bool o_nan = std::isnan(o.min_j), nan = std::isnan(min_j);
    if (o.element >= 0 && (element < 0 || (!nan && (o_nan || o.min_j < min_j)))) {
      min_j = o.min_j;
      element = o.element;
    }
    strain += o.strain;
    hourglass += o.hourglass;
  }
};

template <typename T>
struct Surface {
  std::vector<Vec3<T>> vertices;
  std::vector<std::array<std::int32_t, 3>> triangles;
  std::vector<Vec3<T>> normals;
  SurfaceGrid grid;
  SurfaceLists<T> lists;  // make_surface_lists(grid, vertices, triangles)
  SurfaceView<T> view() const {
    SurfaceView<T> v;
    v.vertices = vertices.data();
    v.triangles = triangles.data();
    v.normals = normals.data();
    v.triangle_count = static_cast<std::int32_t>(triangles.size());
    v.cell_offsets = grid.cell_offsets.data();
    v.cell_triangles = grid.cell_triangles.data();
    v.entry_corners = lists.corners.data();
    v.cell_boxes = lists.cell.data();
    for (int k = 0; k < 3; ++k) {
      v.origin[k] = T(grid.origin[std::size_t(k)]);
      v.dims[k] = grid.dims[std::size_t(k)];
    }
    v.cell = T(grid.cell);
    return v;
  }
};

template <typename T>
struct LoadSet {
  std::vector<Index> nodes;
  Vec3<T> per_node{};  // N (forces) or m (prescribed value)
  bool components[3] = {true, true, true};
  Curve curve;
};

template <typename T>
Vec3<T> to_vec(const std::array<double, 3>& a) {
  return {T(a[0]), T(a[1]), T(a[2])};
}

template <typename T>
class CpuEngine final : public Backend {
 public:
  CpuEngine(const formats::Model& model, const Setup& setup, Plan plan);

  std::string name() const override { return "cpu"; }
  const Plan& plan() const override { return plan_; }
  void step(std::int64_t n) override {
    for (std::int64_t k = 0; k < n; ++k) single_step();
  }
  std::int64_t step_index() const override { return step_; }
  double time() const override { return double(step_) * dt_; }
  double dt() const override { return dt_; }
  State state() const override;
  void restore(const State& s) override;
  std::vector<double> displacements() const override { return flatten(u_); }
  std::vector<double> velocities() const override;
  std::vector<double> internal_forces() override {
    ensure_forces(false);
    return flatten(f_);
  }
  std::array<double, 3> reaction(const std::vector<Index>& nodes) override;
  Energies energies() override;
  ElementFields element_fields() override;

 private:
  static std::vector<double> flatten(const std::vector<Vec3<T>>& v) {
    std::vector<double> out(v.size() * 3);
    for (std::size_t i = 0; i < v.size(); ++i) {
      out[3 * i] = double(v[i].x);
      out[3 * i + 1] = double(v[i].y);
      out[3 * i + 2] = double(v[i].z);
    }
    return out;
  }
  double curve_time(double t) const { return t / setup_.time_scaling; }
  void ensure_forces(bool energy) {
    if (!forces_valid_ || (energy && !energy_valid_)) compute_forces(energy);
  }
  void compute_forces(bool energy);
  template <bool kElastic, bool kMuscle, bool kHourglass, bool kEnergy>
  void element_pass(const std::vector<Index>& elements, std::vector<ElementCheck>& partial);
  template <bool kMuscle, bool kEnergy>
  void element_pass(const std::vector<Index>& elements, std::vector<ElementCheck>& partial);
  template <bool kGravity>
  void update_nodes(std::vector<char>& bad);
  template <bool kElastic, bool kMuscle>
  void element_field_pass(ElementFields& out) const;
  physics::MuscleEntries<T> muscle_entries(std::size_t e) const {
    if (muscle_offset_.empty()) return {nullptr, nullptr, nullptr, nullptr, nullptr, 0, 0};
    return {muscle_id_.data(),     muscle_fraction_.data(), muscle_fibre_.data(),
            muscle_params_.data(), activation_.data(),      muscle_offset_[e],
            muscle_offset_[e + 1]};
  }
  void gather();
  void single_step();
  void apply_constraints(std::vector<Vec3<T>>& u, double t_next);
  double kinetic_energy() const;
  void set_activation(double t);
  std::array<double, 3> rest_position(Index node) const {
    return {double(rest_[std::size_t(node)].x), double(rest_[std::size_t(node)].y),
            double(rest_[std::size_t(node)].z)};
  }
  [[noreturn]] void fail_element(const ElementCheck& c, const char* what) const;
  double blowup_reference() const;

  Setup setup_;
  Plan plan_;
  int threads_ = 1;
  T h_;
  double dt_;
  std::size_t n_, e_;
  std::vector<std::array<Index, 8>> elem_nodes_;
  std::vector<std::int32_t> row_;
  std::vector<physics::ElementRow<T>> rows_;
  std::vector<Vec3<T>> rest_;
  std::vector<Index> dominant_material_;
  // muscles (only when simulated)
  std::vector<std::int64_t> muscle_offset_;
  std::vector<std::int32_t> muscle_id_;
  std::vector<T> muscle_fraction_;
  std::vector<Vec3<T>> muscle_fibre_;
  std::vector<physics::MuscleParams<T>> muscle_params_;
  std::vector<T> activation_;
  double active_energy_bound_ = 0;
  // forces
  std::vector<Vec3<T>> elem_force_;
  std::vector<std::int64_t> inc_offset_;
  std::vector<std::int32_t> inc_;
  std::vector<Vec3<T>> f_;
  std::vector<T> inv_mass_;
  std::vector<Vec3<T>> gravity_;
  physics::CentralDifference<T> cd_;
  // constraints and loads
  std::vector<LoadSet<T>> forces_, prescribed_;
  std::vector<std::vector<Vec3<T>>> prescribed_free_;  // u* before constraints, per set
  std::vector<Index> plane_nodes_;
  std::vector<Vec3<T>> plane_normals_;
  std::vector<Index> rigid_;
  std::vector<Surface<T>> surfaces_;
  std::vector<Index> slide_node_;
  std::vector<std::int32_t> slide_surface_;
  std::vector<T> slide_distance_;
  std::vector<std::int32_t> slide_triangle_;
  // dynamic state
  std::vector<Vec3<T>> u_, up_, un_;
  std::int64_t step_ = 0;
  double external_work_ = 0;
  double initial_energy_ = 0;
  double energy_floor_ = 0;
  bool forces_valid_ = false, energy_valid_ = false;
  ElementCheck last_check_;
};

template <typename T>
CpuEngine<T>::CpuEngine(const formats::Model& model, const Setup& setup, Plan plan)
    : setup_(setup), plan_(std::move(plan)) {
  threads_ = setup.threads > 0 ? setup.threads : omp_get_max_threads();
  // The shared preparation (prepared_model.hpp), converted to T with T(x) as every backend does.
  PreparedModel p = prepare_model(model, setup, plan_);
  const Effects& fx = setup.effects;
  h_ = T(p.h);
  dt_ = plan_.dt;
  n_ = p.nodes;
  e_ = p.elements;
  elem_nodes_ = std::move(p.element_nodes);
  row_ = std::move(p.row);
  rows_.reserve(p.rows.size());
  for (const auto& r : p.rows) rows_.push_back({T(r[0]), T(r[1]), T(r[2])});
  rest_.reserve(n_);
  for (const auto& r : p.rest) rest_.push_back(to_vec<T>(r));
  dominant_material_ = std::move(p.dominant_material);
  // Round-off of the strain energy in T: Ī1 − 3 and (J − 1)² carry errors of order ε.
  energy_floor_ = double(std::numeric_limits<T>::epsilon()) * p.volume * p.min_modulus;
  inv_mass_.resize(n_);
  for (std::size_t i = 0; i < n_; ++i) inv_mass_[i] = T(1.0 / p.mass[i]);
  cd_ = physics::central_difference<T>(dt_, fx.damping ? setup.damping_alpha : 0.0);
  gravity_.reserve(p.gravity.size());
  for (const auto& g : p.gravity) gravity_.push_back(to_vec<T>(g));
  inc_offset_ = std::move(p.incidence_offset);
  inc_ = std::move(p.incidence);
  elem_force_.assign(e_ * 8, Vec3<T>{T(0), T(0), T(0)});
  f_.assign(n_, Vec3<T>{T(0), T(0), T(0)});

  if (fx.muscles) {
    muscle_offset_ = std::move(p.muscle_offset);
    muscle_id_ = std::move(p.muscle_id);
    for (double w : p.muscle_fraction) muscle_fraction_.push_back(T(w));
    for (const auto& a : p.muscle_fibre) muscle_fibre_.push_back(to_vec<T>(a));
    for (const auto& m : p.muscle_params)
      muscle_params_.push_back({T(m[0]), T(m[1]), T(m[2]), T(m[3]), T(m[4])});
    active_energy_bound_ = p.active_energy_bound;
    activation_.assign(model.muscles.size(), T(0));
  }

  const auto load_set = [](const PreparedLoadSet& l) {
    LoadSet<T> s;
    s.nodes = l.nodes;
    s.per_node = to_vec<T>(l.per_node);
    for (int d = 0; d < 3; ++d) s.components[d] = l.components[std::size_t(d)];
    s.curve = l.curve;
    return s;
  };
  for (const auto& l : p.forces) forces_.push_back(load_set(l));
  for (const auto& l : p.prescribed) {
    prescribed_.push_back(load_set(l));
    prescribed_free_.emplace_back(l.nodes.size());
  }
  plane_nodes_ = std::move(p.plane_nodes);
  for (const auto& nrm : p.plane_normals) plane_normals_.push_back(to_vec<T>(nrm));
  rigid_ = std::move(p.rigid);

  for (auto& ps : p.surfaces) {
    Surface<T> surf;
    for (const auto& v : ps.vertices) surf.vertices.push_back(to_vec<T>(v));
    surf.triangles = std::move(ps.triangles);
    for (const auto& t : surf.triangles)
      surf.normals.push_back(physics::triangle_normal(surf.vertices[std::size_t(t[0])],
                                                      surf.vertices[std::size_t(t[1])],
                                                      surf.vertices[std::size_t(t[2])]));
    surf.grid = std::move(ps.grid);
    surf.lists = make_surface_lists(surf.grid, surf.vertices, surf.triangles);
    surfaces_.push_back(std::move(surf));
  }
  slide_node_ = std::move(p.slide_node);
  slide_surface_ = std::move(p.slide_surface);
  for (double d : p.slide_distance) slide_distance_.push_back(T(d));
  slide_triangle_ = std::move(p.slide_triangle);

  // Initial state: u(0) = 0 with the constraints at t = 0; u(−1) = u(0) − v0 Δt.
  u_.assign(n_, Vec3<T>{T(0), T(0), T(0)});
  un_ = u_;
  apply_constraints(u_, 0.0);
  up_ = u_;
  for (const auto& v : setup.initial_velocities)
    for (auto n : v.nodes)
      for (int k = 0; k < 3; ++k)
        up_[std::size_t(n)][k] = u_[std::size_t(n)][k] - T(v.velocity[std::size_t(k)] * dt_);
  for (auto n : rigid_) up_[std::size_t(n)] = u_[std::size_t(n)];
  const Energies e0 = energies();
  initial_energy_ = std::max(0.0, e0.kinetic + e0.strain + e0.hourglass);
  forces_valid_ = energy_valid_ = false;
}

template <typename T>
template <bool kElastic, bool kMuscle, bool kHourglass, bool kEnergy>
void CpuEngine<T>::element_pass(const std::vector<Index>& elements,
                                std::vector<ElementCheck>& partial) {
  const std::size_t chunks = chunk_count(elements.size());
  partial.assign(chunks, ElementCheck{});
  const T h = h_;
#pragma omp parallel for schedule(dynamic, 1) \
    num_threads(threads_) if (elements.size() >= kParallelMin)
  for (std::size_t c = 0; c < chunks; ++c) {
    DenormalGuard<T> guard;
    ElementCheck check;
    double strain = 0, hg_energy = 0;
    const std::size_t end = std::min(elements.size(), (c + 1) * kChunk);
    for (std::size_t i = c * kChunk; i < end; ++i) {
      const auto e = std::size_t(elements[i]);
      const auto& nodes = elem_nodes_[e];
      Vec3<T> u[8];
      for (int a = 0; a < 8; ++a) u[a] = u_[std::size_t(nodes[std::size_t(a)])];
      Vec3<T> fe[8];
      const T j = physics::element_forces<T, kElastic, kMuscle, kHourglass, kEnergy>(
          u, h, rows_[std::size_t(row_[e])], muscle_entries(e), fe, strain, hg_energy);
      const double jd = double(j);  // track the smallest J; the first NaN wins
      if (check.element < 0 || (!std::isnan(check.min_j) && (std::isnan(jd) || jd < check.min_j))) {
        check.min_j = jd;
        check.element = Index(e);
      }
      Vec3<T>* out = &elem_force_[e * 8];
      for (int a = 0; a < 8; ++a) out[a] = fe[a];
    }
    check.strain = strain;
    check.hourglass = hg_energy;
    partial[c] = check;
  }
}

template <typename T>
template <bool kMuscle, bool kEnergy>
void CpuEngine<T>::element_pass(const std::vector<Index>& elements,
                                std::vector<ElementCheck>& partial) {
  const bool elastic = setup_.effects.elasticity, hourglass = setup_.effects.hourglass;
  if (elastic && hourglass) {
    element_pass<true, kMuscle, true, kEnergy>(elements, partial);
  } else if (elastic) {
    element_pass<true, kMuscle, false, kEnergy>(elements, partial);
  } else if (hourglass) {
    element_pass<false, kMuscle, true, kEnergy>(elements, partial);
  } else {
    element_pass<false, kMuscle, false, kEnergy>(elements, partial);
  }
}

template <typename T>
void CpuEngine<T>::gather() {
  const std::size_t chunks = chunk_count(n_);
#pragma omp parallel for schedule(static) num_threads(threads_) if (n_ >= kParallelMin)
  for (std::size_t c = 0; c < chunks; ++c) {
    DenormalGuard<T> guard;
    for (std::size_t i = c * kChunk; i < std::min(n_, (c + 1) * kChunk); ++i) {
      f_[i] = physics::gather_node_force(elem_force_.data(), inc_.data(), inc_offset_[i],
                                         inc_offset_[i + 1]);
    }
  }
}

template <typename T>
void CpuEngine<T>::set_activation(double t) {
  for (std::size_t m = 0; m < activation_.size(); ++m) {
    const double a = m < setup_.activation.size() && !setup_.activation[m].points.empty()
                         ? std::clamp(setup_.activation[m].at(curve_time(t)), 0.0, 1.0)
                         : 0.0;
    activation_[m] = T(a);
  }
}

template <typename T>
void CpuEngine<T>::compute_forces(bool energy) {
  if (setup_.effects.muscles) set_activation(time());
  ElementCheck total;
  std::vector<ElementCheck> partial;
  for (const auto& c : plan_.collections) {
    if (c.muscle) {
      energy ? element_pass<true, true>(c.elements, partial)
             : element_pass<true, false>(c.elements, partial);
    } else {
      energy ? element_pass<false, true>(c.elements, partial)
             : element_pass<false, false>(c.elements, partial);
    }
    for (const auto& p : partial) total.merge(p);
  }
  gather();
  last_check_ = total;
  forces_valid_ = true;
  energy_valid_ = energy;
}

template <typename T>
double CpuEngine<T>::kinetic_energy() const {
  const std::size_t chunks = chunk_count(n_);
  std::vector<double> partial(chunks, 0.0);
  const double inv_dt = 1.0 / dt_;
#pragma omp parallel for schedule(static) num_threads(threads_) if (n_ >= kParallelMin)
  for (std::size_t c = 0; c < chunks; ++c) {
    double s = 0;
    for (std::size_t i = c * kChunk; i < std::min(n_, (c + 1) * kChunk); ++i) {
      const double vx = (double(u_[i].x) - double(up_[i].x)) * inv_dt;
      const double vy = (double(u_[i].y) - double(up_[i].y)) * inv_dt;
      const double vz = (double(u_[i].z) - double(up_[i].z)) * inv_dt;
      s += 0.5 / double(inv_mass_[i]) * (vx * vx + vy * vy + vz * vz);
    }
    partial[c] = s;
  }
  double s = 0;
  for (double p : partial) s += p;
  return s;
}

template <typename T>
void CpuEngine<T>::fail_element(const ElementCheck& c, const char* what) const {
  const auto e = std::size_t(c.element);
  const auto p = rest_position(elem_nodes_[e][0]);
  const double hh = double(h_) / 2;
  throw InstabilityError(
      "", "simulation",
      fmt::format(
          "{} at step {}, t = {:.6g} s: element {} (rest centre ({:.6g}, {:.6g}, {:.6g}) m) "
          "has J = {:.6g}; Δt = {:.6g} s. Lower the time step (or its safety factor), "
          "or check the loads",
          what, step_, time(), c.element, p[0] + hh, p[1] + hh, p[2] + hh, c.min_j, dt_))
      .at(c.element);
}

template <typename T>
double CpuEngine<T>::blowup_reference() const {
  return std::max(0.0, initial_energy_) + std::abs(external_work_) + active_energy_bound_ +
         energy_floor_;
}

template <typename T>
void CpuEngine<T>::single_step() {
  const double t = time();
  const bool check_energy = (step_ % setup_.energy_interval) == 0;
  ensure_forces(check_energy);
  if (last_check_.element >= 0 && !(last_check_.min_j > 0)) {
    fail_element(last_check_,
                 std::isnan(last_check_.min_j) ? "NaN deformation" : "inverted element (J ≤ 0)");
  }
  if (check_energy) {
    const double ke = kinetic_energy();
    const double total = ke + last_check_.strain + last_check_.hourglass;
    if (!std::isfinite(total) || ke > setup_.blowup_factor * blowup_reference()) {
      // Worst node: the fastest.
      std::size_t worst = 0;
      double vmax = -1;
      for (std::size_t i = 0; i < n_; ++i) {
        const double v = squared_norm(u_[i] - up_[i]);
        if (v > vmax || std::isnan(v)) {
          vmax = v;
          worst = i;
          if (std::isnan(v)) break;
        }
      }
      const auto p = rest_position(Index(worst));
      throw InstabilityError(
          "", "simulation",
          fmt::format(
              "kinetic energy blow-up at step {}, t = {:.6g} s: {:.6g} J > {} × {:.6g} J "
              "(initial energy + |external work| + active-muscle bound); fastest node {} "
              "(rest position ({:.6g}, {:.6g}, {:.6g}) m, speed {:.6g} m/s); Δt = {:.6g} s. "
              "Lower the time step (or its safety factor)",
              step_, t, ke, setup_.blowup_factor, blowup_reference(), worst, p[0], p[1], p[2],
              std::sqrt(vmax) / dt_, dt_))
          .at(std::int64_t(worst));
    }
  }

  // Central-difference update of every node (gravity folded in).
  const bool gravity = setup_.effects.gravity;
  const std::size_t chunks = chunk_count(n_);
  std::vector<char> bad(chunks, 0);
  gravity ? update_nodes<true>(bad) : update_nodes<false>(bad);
  for (std::size_t c = 0; c < chunks; ++c) {
    if (!bad[c]) continue;
    for (std::size_t i = c * kChunk; i < std::min(n_, (c + 1) * kChunk); ++i) {
      const auto& v = un_[i];
      if (std::isfinite(double(v.x)) && std::isfinite(double(v.y)) && std::isfinite(double(v.z)))
        continue;
      const auto p = rest_position(Index(i));
      throw InstabilityError(
          "", "simulation",
          fmt::format("non-finite displacement (NaN/Inf) at step {}, t = {:.6g} s: "
                      "node {} (rest position ({:.6g}, {:.6g}, {:.6g}) m); "
                      "Δt = {:.6g} s. Lower the time step (or its safety factor), or check "
                      "the loads",
                      step_ + 1, t + dt_, i, p[0], p[1], p[2], dt_))
          .at(std::int64_t(i));
    }
  }
  // Nodal forces (applied at t_n), added through A = a/M.
  double work = 0;
  for (const auto& s : forces_) {
    const T k = T(s.curve.at(curve_time(t)));
    const Vec3<T> fn = k * s.per_node;
    for (auto n : s.nodes) {
      const auto i = std::size_t(n);
      physics::add_nodal_force(cd_, inv_mass_[i], fn, un_[i]);
    }
  }
  // Keep u* of prescribed nodes: the constraint force is (u − u*)/A.
  for (std::size_t s = 0; s < prescribed_.size(); ++s)
    for (std::size_t k = 0; k < prescribed_[s].nodes.size(); ++k)
      prescribed_free_[s][k] = un_[std::size_t(prescribed_[s].nodes[k])];

  apply_constraints(un_, t + dt_);

  // External work over this step, centred: W += R_n · (u(n+1) − u(n−1)) / 2.
  for (const auto& s : forces_) {
    const double k = s.curve.at(curve_time(t));
    for (auto n : s.nodes) {
      const auto i = std::size_t(n);
      for (int d = 0; d < 3; ++d)
        work += k * double(s.per_node[d]) * 0.5 * (double(un_[i][d]) - double(up_[i][d]));
    }
  }
  for (std::size_t s = 0; s < prescribed_.size(); ++s)
    for (std::size_t k = 0; k < prescribed_[s].nodes.size(); ++k) {
      const auto i = std::size_t(prescribed_[s].nodes[k]);
      const double a = double(cd_.a_over_inverse_mass) * double(inv_mass_[i]);
      for (int d = 0; d < 3; ++d) {
        const double fc = (double(un_[i][d]) - double(prescribed_free_[s][k][d])) / a;
        work += fc * 0.5 * (double(un_[i][d]) - double(up_[i][d]));
      }
    }
  if (gravity) {
    std::vector<double> partial(chunks, 0.0);
#pragma omp parallel for schedule(static) num_threads(threads_) if (n_ >= kParallelMin)
    for (std::size_t c = 0; c < chunks; ++c) {
      double s = 0;
      for (std::size_t i = c * kChunk; i < std::min(n_, (c + 1) * kChunk); ++i)
        for (int d = 0; d < 3; ++d)
          s += double(gravity_[i][d]) * 0.5 * (double(un_[i][d]) - double(up_[i][d]));
      partial[c] = s;
    }
    for (double p : partial) work += p;
  }
  external_work_ += work;

  std::swap(up_, u_);
  std::swap(u_, un_);
  ++step_;
  forces_valid_ = energy_valid_ = false;
}

template <typename T>
template <bool kGravity>
void CpuEngine<T>::update_nodes(std::vector<char>& bad) {
  const Vec3<T> no_gravity{T(0), T(0), T(0)};
#pragma omp parallel for schedule(static) num_threads(threads_) if (n_ >= kParallelMin)
  for (std::size_t c = 0; c < bad.size(); ++c) {
    DenormalGuard<T> guard;
    char b = 0;
    for (std::size_t i = c * kChunk; i < std::min(n_, (c + 1) * kChunk); ++i) {
      const Vec3<T> v = physics::node_update<T, kGravity>(
          cd_, inv_mass_[i], f_[i], kGravity ? gravity_[i] : no_gravity, u_[i], up_[i]);
      un_[i] = v;
      if (!(std::isfinite(double(v.x)) && std::isfinite(double(v.y)) && std::isfinite(double(v.z))))
        b = 1;
    }
    bad[c] = b;
  }
}

template <typename T>
void CpuEngine<T>::apply_constraints(std::vector<Vec3<T>>& u, double t_next) {
  // 1. sliding surfaces
  if (!slide_node_.empty()) {
    const std::int64_t count = std::int64_t(slide_node_.size());
#pragma omp parallel for schedule(static) \
    num_threads(threads_) if (slide_node_.size() >= kParallelMin)
    for (std::int64_t b = 0; b < count; ++b) {
      const auto k = std::size_t(b);
      const auto i = std::size_t(slide_node_[k]);
      const SurfaceView<T> view = surfaces_[std::size_t(slide_surface_[k])].view();
      u[i] = physics::slide_node(view, rest_[i], u[i], slide_distance_[k], slide_triangle_[k]);
    }
  }
  // 2. sliding planes (symmetry)
  for (std::size_t k = 0; k < plane_nodes_.size(); ++k) {
    auto& v = u[std::size_t(plane_nodes_[k])];
    v = physics::project_to_plane(v, plane_normals_[k]);
  }
  // 3. prescribed displacements
  for (const auto& s : prescribed_) {
    const T c = T(s.curve.at(curve_time(t_next)));
    for (auto n : s.nodes) physics::prescribe(c, s.per_node, s.components, u[std::size_t(n)]);
  }
  // 4. rigid nodes
  for (auto n : rigid_) u[std::size_t(n)] = Vec3<T>{T(0), T(0), T(0)};
}

template <typename T>
std::vector<double> CpuEngine<T>::velocities() const {
  std::vector<double> v(3 * n_);
  for (std::size_t i = 0; i < n_; ++i)
    for (int d = 0; d < 3; ++d)
      v[3 * i + std::size_t(d)] = (double(u_[i][d]) - double(up_[i][d])) / dt_;
  return v;
}

template <typename T>
std::array<double, 3> CpuEngine<T>::reaction(const std::vector<Index>& nodes) {
  ensure_forces(false);
  // External loads at t_n on these nodes (gravity, nodal forces): the support carries f − R.
  std::vector<char> in(n_, 0);
  for (auto n : nodes) {
    if (n < 0 || std::size_t(n) >= n_)
      throw ConfigError("", "reaction", fmt::format("node id {} out of range [0, {})", n, n_));
    in[std::size_t(n)] = 1;
  }
  std::array<double, 3> r{0, 0, 0};
  for (auto n : nodes) {
    const auto i = std::size_t(n);
    for (int d = 0; d < 3; ++d) {
      r[std::size_t(d)] += double(f_[i][d]);
      if (setup_.effects.gravity) r[std::size_t(d)] -= double(gravity_[i][d]);
    }
  }
  for (const auto& s : forces_) {
    const double k = s.curve.at(curve_time(time()));
    for (auto n : s.nodes)
      if (in[std::size_t(n)])
        for (int d = 0; d < 3; ++d) r[std::size_t(d)] -= k * double(s.per_node[d]);
  }
  return r;
}

template <typename T>
Energies CpuEngine<T>::energies() {
  ensure_forces(true);
  Energies e;
  e.step = step_;
  e.time = time();
  e.kinetic = kinetic_energy();
  e.strain = last_check_.strain;
  e.hourglass = last_check_.hourglass;
  e.external_work = external_work_;
  return e;
}

template <typename T>
ElementFields CpuEngine<T>::element_fields() {
  if (setup_.effects.muscles) set_activation(time());
  ElementFields out;
  out.jacobian.resize(e_);
  out.von_mises.resize(e_);
  out.energy_density.resize(e_);
  out.cauchy.resize(e_);
  out.material = dominant_material_;
  const bool elastic = setup_.effects.elasticity, muscles = setup_.effects.muscles;
  if (elastic && muscles) {
    element_field_pass<true, true>(out);
  } else if (elastic) {
    element_field_pass<true, false>(out);
  } else if (muscles) {
    element_field_pass<false, true>(out);
  } else {
    element_field_pass<false, false>(out);
  }
  return out;
}

template <typename T>
template <bool kElastic, bool kMuscle>
void CpuEngine<T>::element_field_pass(ElementFields& out) const {
  const std::int64_t count = std::int64_t(e_);
#pragma omp parallel for schedule(static) num_threads(threads_) if (e_ >= kParallelMin)
  for (std::int64_t ei = 0; ei < count; ++ei) {
    const auto e = std::size_t(ei);
    Vec3<T> u[8];
    for (int a = 0; a < 8; ++a) u[a] = u_[std::size_t(elem_nodes_[e][std::size_t(a)])];
    T j;
    SymMat3<T> sigma;
    double w;
    physics::element_field<T, kElastic, kMuscle>(u, h_, rows_[std::size_t(row_[e])],
                                                 muscle_entries(e), j, sigma, w);
    out.jacobian[e] = double(j);
    out.von_mises[e] = double(physics::von_mises(sigma));
    for (int k = 0; k < 6; ++k) out.cauchy[e][std::size_t(k)] = double(sigma.s[k]);
    out.energy_density[e] = w;
  }
}

template <typename T>
State CpuEngine<T>::state() const {
  State s;
  s.step = step_;
  s.time = time();
  s.dt = dt_;
  s.u = flatten(u_);
  s.u_prev = flatten(up_);
  s.sliding_triangle = slide_triangle_;
  s.external_work = external_work_;
  s.energy_reference = initial_energy_;
  return s;
}

template <typename T>
void CpuEngine<T>::restore(const State& s) {
  if (s.u.size() != 3 * n_ || s.u_prev.size() != 3 * n_)
    throw ConfigError("", "state.u",
                      fmt::format("state has {} values, the model needs {}", s.u.size(), 3 * n_));
  if (s.dt != dt_)
    throw ConfigError(
        "", "state.dt",
        fmt::format("state written with Δt = {:.17g} s, this run has {:.17g} s", s.dt, dt_));
  if (s.sliding_triangle.size() != slide_triangle_.size())
    throw ConfigError("", "state.sliding_triangle",
                      fmt::format("{} entries, this run has {} sliding nodes",
                                  s.sliding_triangle.size(), slide_triangle_.size()));
  if (s.step < 0) throw ConfigError("", "state.step", "negative step");
  for (std::size_t i = 0; i < n_; ++i)
    for (int d = 0; d < 3; ++d) {
      u_[i][d] = T(s.u[3 * i + std::size_t(d)]);
      up_[i][d] = T(s.u_prev[3 * i + std::size_t(d)]);
    }
  slide_triangle_ = s.sliding_triangle;
  step_ = s.step;
  external_work_ = s.external_work;
  initial_energy_ = s.energy_reference;
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
