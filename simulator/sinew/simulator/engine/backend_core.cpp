#include "sinew/simulator/engine/backend_core.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include <fmt/format.h>

#include "sinew/common/error.hpp"
#include "sinew/simulator/engine/constraint_report.hpp"
#include "sinew/simulator/passes/cpu_for_each.hpp"
#include "sinew/simulator/passes/effect_dispatch.hpp"
#include "sinew/simulator/physics/hex8.hpp"

namespace sinew::simulator {
namespace {

template <typename T>
Vec3<T> to_vec(const std::array<double, 3>& a) {
  return {T(a[0]), T(a[1]), T(a[2])};
}

template <typename T>
std::vector<Vec3<T>> to_vecs(const std::vector<std::array<double, 3>>& v) {
  std::vector<Vec3<T>> out;
  out.reserve(v.size());
  for (const auto& a : v) out.push_back(to_vec<T>(a));
  return out;
}

template <typename To, typename From>
std::vector<To> convert(const std::vector<From>& v) {
  return std::vector<To>(v.begin(), v.end());
}

std::int32_t to_i32(std::int64_t v, const char* what) {
  if (v > std::int64_t(std::numeric_limits<std::int32_t>::max()))
    throw ConfigError("", "model", fmt::format("too many {} for 32-bit tables", what));
  return std::int32_t(v);
}

// The constraint program in the one order of loads and constraints: per node, nodal forces by set,
// capture of u* (prescribed entries), sliding, planes in list order, lip contact, prescribed sets
// in order, jaw, rigid. Grouped by node (ascending ids: neighbouring sliding nodes share GPU
// warps).
}  // namespace

template <typename T>
ConstraintArrays<T> make_constraint_program(const PreparedModel& p) {
  struct Entry {
    std::int32_t node, code;
  };
  std::vector<Entry> ops;
  auto add = [&](Index node, ConstraintOp kind, std::size_t arg) {
    if (arg > std::size_t(kOpArg)) throw ConfigError("", "model", "too many constraint entries");
    ops.push_back({std::int32_t(node), std::int32_t(kind) << kOpShift | std::int32_t(arg)});
  };
  ConstraintArrays<T> c;
  for (std::size_t s = 0; s < p.forces.size(); ++s) {
    for (auto nd : p.forces[s].nodes) add(nd, kOpForce, s);
    c.force_per_node.push_back(to_vec<T>(p.forces[s].per_node));
  }
  for (std::size_t s = 0; s < p.prescribed.size(); ++s) {
    const auto& pd = p.prescribed[s];
    for (auto nd : pd.nodes) {
      add(nd, kOpCapture, c.prescribed_set.size());
      c.prescribed_set.push_back(std::int32_t(s));
    }
    c.prescribed_value.push_back(to_vec<T>(pd.per_node));
    c.prescribed_mask.push_back((pd.components[0] ? 1 : 0) | (pd.components[1] ? 2 : 0) |
                                (pd.components[2] ? 4 : 0));
  }
  // The jaw's nodes: a capture each (u* for the work, as a prescribed entry's), then their move.
  const std::size_t jaw_entry = c.prescribed_set.size();
  for (auto nd : p.jaw_nodes) {
    add(nd, kOpCapture, c.prescribed_set.size());
    c.prescribed_set.push_back(-1);
  }
  for (std::size_t k = 0; k < p.slide_node.size(); ++k) add(p.slide_node[k], kOpSlide, k);
  for (std::size_t k = 0; k < p.plane_nodes.size(); ++k) {
    add(p.plane_nodes[k], kOpPlane, k);
    c.plane_normal.push_back(to_vec<T>(p.plane_normals[k]));
  }
  for (std::size_t k = 0; k < p.contact_node.size(); ++k) {
    add(p.contact_node[k], kOpContact, k);
    c.contact_partner.push_back(std::int32_t(p.contact_partner[k]));
    c.contact_share.push_back(T(p.contact_share[k]));
  }
  c.contact_up = to_vec<T>(p.contact_up);
  {
    std::size_t q = 0;
    for (const auto& pd : p.prescribed)
      for (auto nd : pd.nodes) add(nd, kOpPrescribe, q++);
  }
  for (std::size_t k = 0; k < p.jaw_nodes.size(); ++k) add(p.jaw_nodes[k], kOpJaw, jaw_entry + k);
  if (!p.jaw_nodes.empty()) c.jaw_factor = std::int32_t(p.forces.size() + p.prescribed.size());
  for (auto nd : p.rigid) add(nd, kOpRigid, 0);
  std::stable_sort(ops.begin(), ops.end(),
                   [](const Entry& x, const Entry& y) { return x.node < y.node; });
  c.offset.push_back(0);
  for (std::size_t k = 0; k < ops.size(); ++k) {
    if (k == 0 || ops[k].node != ops[k - 1].node) {
      if (k) c.offset.push_back(std::int32_t(k));
      c.node.push_back(ops[k].node);
    }
    c.op.push_back(ops[k].code);
  }
  if (!ops.empty()) c.offset.push_back(std::int32_t(ops.size()));
  c.node_op_offset.assign(p.nodes + 1, 0);
  for (std::size_t k = 0; k < c.node.size(); ++k)
    c.node_op_offset[std::size_t(c.node[k]) + 1] = c.offset[k + 1] - c.offset[k];
  for (std::size_t k = 0; k < p.nodes; ++k) c.node_op_offset[k + 1] += c.node_op_offset[k];
  return c;
}

namespace {

template <typename T>
SlidingSurfaceArrays<T> make_surface(const PreparedSurface& ps, double skin_cells) {
  SlidingSurfaceArrays<T> s;
  s.vertices = to_vecs<T>(ps.vertices);
  s.triangles = ps.triangles;
  for (const auto& t : s.triangles)
    s.normals.push_back(physics::triangle_normal(s.vertices[std::size_t(t[0])],
                                                 s.vertices[std::size_t(t[1])],
                                                 s.vertices[std::size_t(t[2])]));
  s.grid = ps.grid;
  s.lists = make_surface_lists(s.grid, s.vertices, s.triangles);
  s.triangle_corners = triangle_corner_list(s.vertices, s.triangles);
  s.skin = T(skin_cells * s.grid.cell);
  return s;
}

}  // namespace

template <typename T>
SurfaceView<T> SlidingSurfaceArrays<T>::view() const {
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

template <typename T>
ElementData<T> EngineArrays<T>::element_data() const {
  return {element_nodes.data(),  row.data(),           rows.data(),
          muscle_offset.data(),  muscle_id.data(),     muscle_fraction.data(),
          muscle_fibre.data(),   muscle_params.data(), h,
          std::int32_t(elements)};
}

template <typename T>
NodeData<T> EngineArrays<T>::node_data(const physics::CentralDifference<T>& cd) const {
  return {inverse_mass.data(),
          gravity.empty() ? nullptr : gravity.data(),
          incidence_offset.data(),
          incidence.data(),
          cd,
          std::int32_t(nodes)};
}

template <typename T>
HostSlidingState<T>::HostSlidingState(const EngineArrays<T>& a)
    : triangle(a.slide_triangle),
      search_triangle(a.slide_triangle),
      list_count(a.slide_node.size(), -1),
      list(a.slide_node.size() * kCandidates),
      list_distance(a.slide_node.size() * kCandidates),
      anchor(a.slide_node.size()) {
  for (const auto& s : a.surfaces)
    surfaces.push_back({s.view(), s.triangle_corners.data(), s.skin});
}

template <typename T>
void HostSlidingState<T>::restore(const std::vector<Index>& triangles) {
  triangle = triangles;
  search_triangle = triangles;
  std::fill(list_count.begin(), list_count.end(), -1);
}

template <typename T>
SlideData<T> HostSlidingState<T>::data(const EngineArrays<T>& a) {
  return {a.slide_node.data(),
          a.slide_surface.data(),
          a.slide_distance.data(),
          triangle.data(),
          search_triangle.data(),
          list_count.data(),
          anchor.data(),
          list.data(),
          list_distance.data(),
          surfaces.data(),
          std::int32_t(a.slide_node.size()),
          nullptr};
}

template <typename T>
ConstraintData<T> host_constraint_data(const EngineArrays<T>& a,
                                       const physics::CentralDifference<T>& cd,
                                       Vec3<T>* prescribed_free, HostSlidingState<T>& sliding) {
  const ConstraintArrays<T>& c = a.constraints;
  return {c.node.data(),
          c.offset.data(),
          c.op.data(),
          std::int32_t(c.node.size()),
          a.inverse_mass.data(),
          cd,
          c.force_per_node.data(),
          c.prescribed_set.data(),
          c.prescribed_value.data(),
          c.prescribed_mask.data(),
          prescribed_free,
          c.plane_normal.data(),
          sliding.data(a),
          a.rest.data(),
          a.gravity.empty() ? nullptr : a.gravity.data(),
          std::int32_t(c.force_per_node.size()),
          c.jaw_factor,
          c.contact_partner.data(),
          c.contact_share.data(),
          c.contact_up};
}

template <typename T>
EngineArrays<T> make_engine_arrays(const PreparedModel& p, double sliding_skin) {
  if (!(sliding_skin > 0) || !std::isfinite(sliding_skin))
    throw ConfigError("", "sliding_skin",
                      fmt::format("must be a positive number of grid cells, got {}", sliding_skin));
  EngineArrays<T> a;
  a.h = T(p.h);
  a.nodes = p.nodes;
  a.elements = p.elements;
  to_i32(std::int64_t(p.elements) * 8, "elements");
  a.element_nodes = p.element_nodes;
  a.row = p.row;
  for (const auto& r : p.rows) a.rows.push_back({T(r.mu), T(r.kappa), T(r.hourglass_k)});
  a.rest = to_vecs<T>(p.rest);
  a.inverse_mass.resize(p.nodes);
  for (std::size_t i = 0; i < p.nodes; ++i) a.inverse_mass[i] = T(1.0 / p.mass[i]);
  a.gravity = to_vecs<T>(p.gravity);
  a.incidence_offset = convert<std::int32_t>(p.incidence_offset);
  a.incidence = p.incidence;
  if (!p.muscle_offset.empty()) {
    to_i32(p.muscle_offset.back(), "muscle entries");
    a.muscle_offset = convert<std::int32_t>(p.muscle_offset);
    a.muscle_id = p.muscle_id;
    a.muscle_fraction = convert<T>(p.muscle_fraction);
    a.muscle_fibre = to_vecs<T>(p.muscle_fibre);
    for (const auto& m : p.muscle_params)
      a.muscle_params.push_back(
          {T(m.reference_stress), T(m.optimal_stretch), T(m.p1), T(m.p2), T(m.linear_stretch)});
  }
  a.constraints = make_constraint_program<T>(p);
  for (const auto& s : p.surfaces) a.surfaces.push_back(make_surface<T>(s, sliding_skin));
  a.slide_node = convert<std::int32_t>(p.slide_node);
  a.slide_surface = p.slide_surface;
  a.slide_triangle = p.slide_triangle;
  a.slide_distance = convert<T>(p.slide_distance);
  return a;
}

template <typename T>
std::vector<double> flatten(const Vec3<T>* v, std::size_t n) {
  std::vector<double> out(3 * n);
  for (std::size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) out[3 * i + std::size_t(d)] = double(v[i][d]);
  return out;
}

template <typename T>
std::vector<Vec3<T>> unflatten(const std::vector<double>& flat) {
  std::vector<Vec3<T>> v(flat.size() / 3);
  for (std::size_t i = 0; i < v.size(); ++i)
    for (int d = 0; d < 3; ++d) v[i][d] = T(flat[3 * i + std::size_t(d)]);
  return v;
}

BackendCore::BackendCore(const formats::Model& model, const Setup& setup, Plan plan)
    : setup_(setup), plan_(std::move(plan)) {
  prepared_ = prepare_model(model, setup, plan_);
  model_rigid_ = model.rigid_nodes;
  muscle_count_ = model.muscles.size();
  force_slots_ = setup.effects.loads ? std::size_t(std::max(0, setup.force_slots)) : 0;
  const double eps = setup.precision == Precision::float32
                         ? double(std::numeric_limits<float>::epsilon())
                         : double(std::numeric_limits<double>::epsilon());
  // The round-off floor of the blow-up test (docs/physics.md "Instability"): the strain energy of
  // a strain of order √ε at the softest modulus, plus the kinetic energy of every node moving by
  // one rounding of its position, ε · |x|, per step: motion the positions cannot resolve. A body
  // at rest in float (sliding projections, elements far from the origin) moves that fast from
  // round-off alone, so without the second term its stop test compared noise with a near-zero
  // reference.
  double extent = 0, mass = 0;
  for (const auto& x : prepared_.rest) extent = std::max(extent, std::hypot(x[0], x[1], x[2]));
  for (double m : prepared_.mass) mass += m;
  const double noise_speed = eps * extent / plan_.dt;
  energy_floor_ =
      eps * prepared_.volume * prepared_.min_modulus + 0.5 * mass * noise_speed * noise_speed;
}

std::size_t BackendCore::step_scalar_count() const {
  return std::max<std::size_t>(1, muscle_count() + prepared_.forces.size() +
                                      prepared_.prescribed.size() +
                                      (setup_.jaw ? std::size_t(physics::kJawMapSize) : 0));
}

double BackendCore::curve_activation(std::size_t m, double t) const {
  return m < setup_.activation.size() ? clamped_activation(setup_.activation[m], curve_time(t))
                                      : 0.0;
}

double BackendCore::activation_value(std::size_t m, std::int64_t step) const {
  const double curve = curve_activation(m, time(step));
  if (m >= activation_override_.size() || !activation_override_[m]) return curve;
  const ActivationOverride& o = *activation_override_[m];
  return ramped_activation(o.from, o.target ? *o.target : curve, o.start, o.ramp, step);
}

template <typename T>
void BackendCore::activations(double t, T* out) const {
  // Times of steps (time(n) = n Δt): the override's ramp counts steps.
  const std::int64_t step = plan_.dt > 0 ? std::llround(t / plan_.dt) : 0;
  for (std::size_t m = 0; m < muscle_count(); ++m) {
    if (m < activation_override_.size() && activation_override_[m]) {
      out[m] = T(activation_value(m, step));
      continue;
    }
    out[m] = T(curve_activation(m, t));
  }
}

void BackendCore::set_activation_override(std::size_t m, std::optional<double> a,
                                          std::int64_t step) {
  if (m >= muscle_count())
    throw ConfigError(
        "", "activation",
        fmt::format("muscle {} out of range (the run simulates {})", m, muscle_count()));
  if (a && !std::isfinite(*a))
    throw ConfigError("", "activation", "the activation must be a finite number");
  // The time step holds up to the activation it was planned for (Setup::max_activation).
  if (a && *a > setup_.max_activation(m))
    throw ConfigError("", "activation",
                      fmt::format("{:.4g} is above {:.4g}, the activation this run's time step was "
                                  "planned for (a live run plans for 1; a played-back run keeps "
                                  "its own plan)",
                                  *a, setup_.max_activation(m)));
  activation_override_.resize(muscle_count());
  auto& o = activation_override_[m];
  if (!a && !o) return;  // on the curve already
  ActivationOverride next;
  // Clamped as the curves are; + 0.0 turns −0 into +0 (the curve of a reproduced scene gives +0).
  if (a) next.target = std::clamp(*a, 0.0, 1.0) + 0.0;
  next.from = activation_value(m, step);
  next.start = step;
  next.ramp = o && step < o->start ? 0 : override_ramp_steps(plan_.dt);
  o = next;
}

std::optional<double> BackendCore::activation_override(std::size_t m) const {
  return m < activation_override_.size() && activation_override_[m]
             ? activation_override_[m]->target
             : std::nullopt;
}

void BackendCore::set_force_slot(std::size_t k, std::vector<Index> nodes,
                                 const std::array<double, 3>& force) {
  if (k >= force_slots_)
    throw ConfigError("", "force slot",
                      fmt::format("slot {} out of range (the run has {})", k, force_slots_));
  check_node_ids(nodes, "force slot nodes");
  for (double f : force)
    if (!std::isfinite(f)) throw ConfigError("", "force", "the force must be finite");
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  auto& set = prepared_.forces[prepared_.forces.size() - force_slots_ + k];
  set.nodes = std::move(nodes);
  set.per_node = force;
  set.curve = Curve::constant(1.0);
}

void BackendCore::clear_force_slot(std::size_t k) {
  if (k >= force_slots_)
    throw ConfigError("", "force slot",
                      fmt::format("slot {} out of range (the run has {})", k, force_slots_));
  auto& set = prepared_.forces[prepared_.forces.size() - force_slots_ + k];
  set.nodes.clear();
  set.per_node = {0, 0, 0};
  set.curve = Curve::constant(0.0);
}

template <typename T>
void BackendCore::step_scalars(std::int64_t step, T* row) const {
  const double t = time(step);
  activations(std::max(0.0, t), row);
  T* force = row + muscle_count();
  for (std::size_t s = 0; s < prepared_.forces.size(); ++s)
    force[s] = T(prepared_.forces[s].curve.at(curve_time(t)));
  T* prescribed = force + prepared_.forces.size();
  for (std::size_t s = 0; s < prepared_.prescribed.size(); ++s)
    prescribed[s] = T(prepared_.prescribed[s].curve.at(curve_time(t + dt())));
  if (setup_.jaw) {
    double map[physics::kJawMapSize];
    jaw_map(t + dt(), map);
    T* jaw = prescribed + prepared_.prescribed.size();
    for (int k = 0; k < physics::kJawMapSize; ++k) jaw[k] = T(map[k]);
  }
}

void BackendCore::jaw_map(double t, double (&map)[physics::kJawMapSize]) const {
  setup_.jaw->map(curve_time(t), map);
}

void BackendCore::set_initial_energy(const Energies& e0) {
  initial_energy_ = std::max(0.0, e0.kinetic + e0.strain + e0.hourglass);
}

BlowupBound BackendCore::blowup_bound() const {
  return {std::max(0.0, initial_energy_) + prepared_.active_energy_bound + energy_floor_,
          setup_.blowup_factor};
}

double BackendCore::blowup_reference(double work) const {
  return std::max(0.0, initial_energy_) + std::abs(work) + prepared_.active_energy_bound +
         energy_floor_;
}

bool BackendCore::blown_up(double kinetic, double strain_and_hourglass, double work) const {
  return !std::isfinite(kinetic + strain_and_hourglass) ||
         kinetic > setup_.blowup_factor * blowup_reference(work);
}

void BackendCore::fail_element(std::int64_t step, Index element, double j) const {
  const auto& p = prepared_.rest[std::size_t(prepared_.element_nodes[std::size_t(element)][0])];
  const double hh = prepared_.h / 2;
  bool behind = false;
  const std::string held = element_constraints(prepared_, setup_, model_rigid_, element, behind);
  // In the first steps only the constraints can have inverted it (constraint_report.hpp): name
  // them instead of advising a smaller step, which would not help.
  std::string advice;
  if (!held.empty() && (step <= kConstraintBlameSteps || behind)) {
    advice = fmt::format(
        "Its corners' constraints: {}. {}: check the model's boundary conditions (sinew-inspect "
        "MODEL --element {}; docs/voxelizer.md, \"Safe constraints\"); a smaller time step will "
        "not help",
        held,
        behind ? "A sliding node lay behind its surface at rest"
               : fmt::format("An element inverted within the first {} steps was inverted by its "
                             "constraints",
                             kConstraintBlameSteps),
        element);
  } else {
    advice = "Lower the time step (or its safety factor), or check the loads";
    if (!held.empty()) advice += ". Its corners' constraints: " + held;
  }
  throw InstabilityError(
      "", "simulation",
      fmt::format(
          "{} at step {}, t = {:.6g} s: element {} (rest centre ({:.6g}, {:.6g}, {:.6g}) m) "
          "has J = {:.6g}; Δt = {:.6g} s. {}",
          std::isnan(j) ? "NaN deformation" : "inverted element (J ≤ 0)", step, time(step), element,
          p[0] + hh, p[1] + hh, p[2] + hh, j, dt(), advice))
      .at(element);
}

void BackendCore::fail_displacement(std::int64_t step, Index node) const {
  if (node < 0)  // flagged on the GPU, not found in the copy: report the step alone
    throw InstabilityError("", "simulation",
                           fmt::format("non-finite displacement at step {}", step));
  const auto& p = prepared_.rest[std::size_t(node)];
  const NodeConstraints held = node_constraints(prepared_, setup_, model_rigid_, node);
  std::string constraints;
  for (const auto& item : held.items) constraints += (constraints.empty() ? "" : ", ") + item;
  throw InstabilityError(
      "", "simulation",
      fmt::format("non-finite displacement (NaN/Inf) at step {}, t = {:.6g} s: "
                  "node {} (rest position ({:.6g}, {:.6g}, {:.6g}) m{}); "
                  "Δt = {:.6g} s. Lower the time step (or its safety factor), or check "
                  "the loads",
                  step, time(step), node, p[0], p[1], p[2],
                  constraints.empty() ? "" : ", " + constraints, dt()))
      .at(std::int64_t(node));
}

void BackendCore::fail_blowup(std::int64_t step, double kinetic, double work, Index fastest,
                              double speed) const {
  const auto& p = prepared_.rest[std::size_t(fastest)];
  // The physical part of the reference; when it is below the round-off floor the body was at
  // rest or barely loaded, and the growth may be noise (float) rather than a too-large step.
  const double physical =
      std::max(0.0, initial_energy_) + std::abs(work) + prepared_.active_energy_bound;
  const std::string advice =
      physical < energy_floor_
          ? fmt::format(
                "The reference was near zero ({:.3g} J of energy and work, below the round-off "
                "floor {:.3g} J): a body at rest or barely loaded, so this may be round-off noise "
                "growing, not a too-large step; try precision double first. Lower the time step "
                "(or its safety factor) if the motion is real",
                physical, energy_floor_)
          : std::string("Lower the time step (or its safety factor)");
  throw InstabilityError(
      "", "simulation",
      fmt::format("kinetic energy blow-up at step {}, t = {:.6g} s: {:.6g} J > {} × {:.6g} J "
                  "(initial energy + |external work| + active-muscle bound + round-off floor); "
                  "fastest node {} (rest position ({:.6g}, {:.6g}, {:.6g}) m, speed {:.6g} m/s); "
                  "Δt = {:.6g} s. {}",
                  step, time(step), kinetic, setup_.blowup_factor, blowup_reference(work), fastest,
                  p[0], p[1], p[2], speed, dt(), advice))
      .at(std::int64_t(fastest));
}

template <typename T>
State BackendCore::make_state(std::int64_t step, const std::vector<Vec3<T>>& u,
                              const std::vector<Vec3<T>>& up, std::vector<Index> sliding_triangle,
                              double external_work) const {
  State s;
  s.step = step;
  s.time = time(step);
  s.dt = dt();
  s.u = flatten(u.data(), u.size());
  s.u_prev = flatten(up.data(), up.size());
  s.sliding_triangle = std::move(sliding_triangle);
  s.external_work = external_work;
  s.energy_reference = initial_energy_;
  return s;
}

void BackendCore::check_node_ids(const std::vector<Index>& ids, const char* what) const {
  for (auto n : ids)
    if (n < 0 || std::size_t(n) >= nodes())
      throw ConfigError("", what, fmt::format("node id {} out of range [0, {})", n, nodes()));
}

void BackendCore::check_state(const State& s) const {
  const std::size_t n = nodes();
  if (s.u.size() != 3 * n || s.u_prev.size() != 3 * n)
    throw ConfigError("", "state.u",
                      fmt::format("state has {} values, the model needs {}", s.u.size(), 3 * n));
  if (s.dt != dt())
    throw ConfigError(
        "", "state.dt",
        fmt::format("state written with Δt = {:.17g} s, this run has {:.17g} s", s.dt, dt()));
  if (s.sliding_triangle.size() != prepared_.slide_triangle.size())
    throw ConfigError("", "state.sliding_triangle",
                      fmt::format("{} entries, this run has {} sliding nodes",
                                  s.sliding_triangle.size(), prepared_.slide_triangle.size()));
  if (s.step < 0) throw ConfigError("", "state.step", "negative step");
  // The engines recompute time as step · Δt; a stored time that disagrees means step, time or Δt
  // is not what the run wrote.
  const double expected = time(s.step);
  if (!(std::abs(s.time - expected) <= kStateTimeTolerance * std::max(expected, dt())))
    throw ConfigError(
        "", "state.time",
        fmt::format(
            "time {:.17g} s is not step · Δt = {} · {:.17g} s = {:.17g} s (to {:g} relative)",
            s.time, s.step, dt(), expected, kStateTimeTolerance));
  // The triangle ids index the surfaces' corners in the step's first sliding pass: one out of
  // range (a damaged checkpoint) read past the array (scripts/fuzz_inputs.py).
  for (std::size_t k = 0; k < s.sliding_triangle.size(); ++k) {
    const auto t = s.sliding_triangle[k];
    const auto& surface = prepared_.surfaces[std::size_t(prepared_.slide_surface[k])];
    if (t < 0 || std::size_t(t) >= surface.triangles.size())
      throw ConfigError("", "state.sliding_triangle",
                        fmt::format("triangle {} out of range [0, {}) of surface '{}'", t,
                                    surface.triangles.size(), surface.name))
          .at(std::int64_t(k));
  }
  for (std::size_t i = 0; i < s.u.size(); ++i) {
    if (!std::isfinite(s.u[i]) || !std::isfinite(s.u_prev[i]))
      throw ConfigError("", std::isfinite(s.u[i]) ? "state.u_prev" : "state.u",
                        "non-finite displacement")
          .at(std::int64_t(i / 3));
  }
}

template <typename T>
double BackendCore::kinetic_energy(const Vec3<T>* u, const Vec3<T>* up, const T* inverse_mass,
                                   int threads) const {
  const std::size_t n = nodes();
  std::vector<double> partial(chunk_count(n), 0.0);
  const double inv_dt = 1.0 / dt();
  for_each_chunk<double>(n, threads, [&](std::size_t c, std::size_t begin, std::size_t end) {
    double s = 0;
    for (std::size_t i = begin; i < end; ++i)
      s += node_kinetic_energy(u[i], up[i], inverse_mass[i], inv_dt);
    partial[c] = s;
  });
  double s = 0;
  for (double p : partial) s += p;
  return s;
}

template <typename T>
Index BackendCore::fastest_node(const Vec3<T>* u, const Vec3<T>* up, double& squared_move) const {
  std::size_t worst = 0;
  double vmax = -1;
  for (std::size_t i = 0; i < nodes(); ++i) {
    const double v = double(squared_norm(u[i] - up[i]));
    if (v > vmax || std::isnan(v)) {
      vmax = v;
      worst = i;
      if (std::isnan(v)) break;
    }
  }
  squared_move = vmax;
  return Index(worst);
}

template <typename T>
Index BackendCore::first_non_finite(const Vec3<T>* u) const {
  for (std::size_t i = 0; i < nodes(); ++i)
    if (!all_finite(u[i])) return Index(i);
  return -1;
}

template <typename T>
Index BackendCore::worst_element(const EngineArrays<T>& a, const Vec3<T>* u, double& j) const {
  double min_j = std::numeric_limits<double>::infinity();
  Index worst = -1;
  for (std::size_t e = 0; e < elements(); ++e) {
    Vec3<T> ue[8];
    for (int c = 0; c < 8; ++c) ue[c] = u[std::size_t(a.element_nodes[e][std::size_t(c)])];
    const double je = double(determinant(physics::hex8_deformation_gradient(ue, a.h)));
    if (worst < 0 || (!std::isnan(min_j) && (std::isnan(je) || je < min_j))) {
      min_j = je;
      worst = Index(e);
    }
  }
  j = min_j;
  return worst;
}

template <typename T>
std::vector<double> BackendCore::velocities(const Vec3<T>* u, const Vec3<T>* up) const {
  std::vector<double> v(3 * nodes());
  for (std::size_t i = 0; i < nodes(); ++i)
    for (int d = 0; d < 3; ++d)
      v[3 * i + std::size_t(d)] = (double(u[i][d]) - double(up[i][d])) / dt();
  return v;
}

template <typename T>
std::array<double, 3> BackendCore::reaction(const EngineArrays<T>& a,
                                            const std::vector<Index>& nodes_in,
                                            const Vec3<T>* set_forces, std::int64_t step) const {
  // External loads at t_n on these nodes (gravity, nodal forces): the support carries f − R.
  check_node_ids(nodes_in, "reaction");
  std::vector<char> in(nodes(), 0);
  for (auto n : nodes_in) in[std::size_t(n)] = 1;
  std::array<double, 3> r{0, 0, 0};
  for (std::size_t k = 0; k < nodes_in.size(); ++k) {
    const auto i = std::size_t(nodes_in[k]);
    for (int d = 0; d < 3; ++d) {
      r[std::size_t(d)] += double(set_forces[k][d]);
      if (!a.gravity.empty()) r[std::size_t(d)] -= double(a.gravity[i][d]);
    }
  }
  for (std::size_t s = 0; s < prepared_.forces.size(); ++s) {
    const double k = prepared_.forces[s].curve.at(curve_time(time(step)));
    for (auto n : prepared_.forces[s].nodes)
      if (in[std::size_t(n)])
        for (int d = 0; d < 3; ++d)
          r[std::size_t(d)] -= k * double(a.constraints.force_per_node[s][d]);
  }
  return r;
}

template <typename T>
ElementFields BackendCore::element_fields(const EngineArrays<T>& a, const Vec3<T>* u,
                                          std::int64_t step, int threads) const {
  std::vector<T> activation(muscle_count());
  activations(time(step), activation.data());
  return fields_at(a, u, activation.data(), threads);
}

template <typename T>
std::function<ElementFields()> BackendCore::deferred_element_fields(const EngineArrays<T>& a,
                                                                    std::vector<Vec3<T>> u,
                                                                    std::int64_t step,
                                                                    int threads) const {
  // The activations are read now: whatever steers them later must not reach this frame.
  std::vector<T> activation(muscle_count());
  activations(time(step), activation.data());
  return [this, &a, u = std::move(u), activation = std::move(activation), threads] {
    return fields_at(a, u.data(), activation.data(), threads);
  };
}

template <typename T>
ElementFields BackendCore::fields_at(const EngineArrays<T>& a, const Vec3<T>* u,
                                     const T* activation, int threads) const {
  const ElementData<T> d = a.element_data();
  const std::size_t e_count = elements();
  ElementFields out;
  out.jacobian.resize(e_count);
  out.von_mises.resize(e_count);
  out.energy_density.resize(e_count);
  out.cauchy.resize(e_count);
  out.material = prepared_.dominant_material;
  dispatch_flags(
      [&](auto elastic, auto muscles) {
        constexpr bool kElastic = decltype(elastic)::value, kMuscle = decltype(muscles)::value;
        for_each_chunk<T>(e_count, threads, [&](std::size_t, std::size_t begin, std::size_t end) {
          for (std::size_t e = begin; e < end; ++e) {
            const ElementStart<T> s = element_start<T, kMuscle>(d, std::int32_t(e), activation);
            Vec3<T> ue[8];
            for (int c = 0; c < 8; ++c) ue[c] = u[s.ids[c]];
            T j;
            SymMat3<T> sigma;
            double w;
            physics::element_field<T, kElastic, kMuscle>(ue, a.h, s.row, s.muscles, j, sigma, w);
            out.jacobian[e] = double(j);
            out.von_mises[e] = double(physics::von_mises(sigma));
            for (int k = 0; k < 6; ++k) out.cauchy[e][std::size_t(k)] = double(sigma.s[k]);
            out.energy_density[e] = w;
          }
        });
      },
      setup_.effects.elasticity, setup_.effects.muscles);
  return out;
}

#define SINEW_BACKEND_CORE_INSTANTIATE(T)                                                        \
  template struct SlidingSurfaceArrays<T>;                                                       \
  template std::vector<double> flatten<T>(const Vec3<T>*, std::size_t);                          \
  template std::vector<Vec3<T>> unflatten<T>(const std::vector<double>&);                        \
  template State BackendCore::make_state<T>(std::int64_t, const std::vector<Vec3<T>>&,           \
                                            const std::vector<Vec3<T>>&, std::vector<Index>,     \
                                            double) const;                                       \
  template struct EngineArrays<T>;                                                               \
  template EngineArrays<T> make_engine_arrays<T>(const PreparedModel&, double);                  \
  template struct HostSlidingState<T>;                                                           \
  template ConstraintData<T> host_constraint_data<T>(const EngineArrays<T>&,                     \
                                                     const physics::CentralDifference<T>&,       \
                                                     Vec3<T>*, HostSlidingState<T>&);            \
  template ConstraintArrays<T> make_constraint_program<T>(const PreparedModel&);                 \
  template void BackendCore::step_scalars<T>(std::int64_t, T*) const;                            \
  template void BackendCore::activations<T>(double, T*) const;                                   \
  template double BackendCore::kinetic_energy<T>(const Vec3<T>*, const Vec3<T>*, const T*, int)  \
      const;                                                                                     \
  template Index BackendCore::fastest_node<T>(const Vec3<T>*, const Vec3<T>*, double&) const;    \
  template Index BackendCore::first_non_finite<T>(const Vec3<T>*) const;                         \
  template Index BackendCore::worst_element<T>(const EngineArrays<T>&, const Vec3<T>*, double&)  \
      const;                                                                                     \
  template std::vector<double> BackendCore::velocities<T>(const Vec3<T>*, const Vec3<T>*) const; \
  template std::array<double, 3> BackendCore::reaction<T>(                                       \
      const EngineArrays<T>&, const std::vector<Index>&, const Vec3<T>*, std::int64_t) const;    \
  template ElementFields BackendCore::element_fields<T>(const EngineArrays<T>&, const Vec3<T>*,  \
                                                        std::int64_t, int) const;                \
  template std::function<ElementFields()> BackendCore::deferred_element_fields<T>(               \
      const EngineArrays<T>&, std::vector<Vec3<T>>, std::int64_t, int) const;
SINEW_BACKEND_CORE_INSTANTIATE(float)
SINEW_BACKEND_CORE_INSTANTIATE(double)
#undef SINEW_BACKEND_CORE_INSTANTIATE

}  // namespace sinew::simulator
