#include "sinew/simulator/engine/plan.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include <fmt/format.h>

#include "sinew/common/error.hpp"
#include "sinew/simulator/physics/muscle.hpp"
#include "sinew/simulator/physics/neo_hookean.hpp"
#include "sinew/simulator/physics/time_step.hpp"

namespace sinew::simulator {
namespace {

// Waves faster than in any solid (diamond's longitudinal sound speed is about 18,000 m/s): a model
// whose stable step implies more has a stiffness out of range.
constexpr double kMaxWaveSpeed = 1e5;  // m/s

[[noreturn]] void bad(const std::string& field, const std::string& problem) {
  throw ConfigError("", field, problem);
}

void check_nodes(const std::vector<Index>& nodes, std::size_t n, const std::string& field) {
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    if (nodes[i] < 0 || static_cast<std::size_t>(nodes[i]) >= n) {
      throw ConfigError("", field, fmt::format("node id {} out of range [0, {})", nodes[i], n))
          .at(static_cast<std::int64_t>(i));
    }
  }
}

std::string human_bytes(std::size_t b) {
  if (b >= (1u << 30)) return fmt::format("{:.2f} GiB", double(b) / double(1u << 30));
  if (b >= (1u << 20)) return fmt::format("{:.2f} MiB", double(b) / double(1u << 20));
  if (b >= (1u << 10)) return fmt::format("{:.1f} KiB", double(b) / double(1u << 10));
  return fmt::format("{} B", b);
}

const char* precision_name(Precision p) {
  return p == Precision::float32 ? "float" : "double";
}
// An automatic step with no finite estimate: say which input makes it so. No stiffness at all is
// the scene's doing (effects off); a stiff model whose h/c is still astronomic has a voxel size
// in the wrong unit (mass_scaling is bounded above, so it cannot be the cause).
[[noreturn]] void explain_no_step(const formats::Model& model, const Plan& plan, double dt_crit,
                                  double max_modulus) {
  if (!(max_modulus > 0))
    throw ConfigError("", "time_step", "no stiffness to estimate a step from; give a user Δt");
  throw ConfigError(
      "", "model.grid.voxel_size",
      fmt::format("the model's voxel size {:.6g} m gives a stable step h/c of {:.3g} s at element "
                  "{}, more than the engine can step; the model's units are wrong (sinew models "
                  "are in metres) or the model is damaged",
                  model.grid.voxel_size, dt_crit, plan.dt_critical_element));
}

const char* modulus_name(HourglassModulus m) {
  return m == HourglassModulus::shear ? "shear (M* = 2μ)" : "p-wave (M* = λ + 2μ)";
}

}  // namespace

std::size_t Plan::total_bytes() const {
  std::size_t s = 0;
  for (const auto& a : arrays) s += a.bytes;
  return s;
}

Plan make_plan(const formats::Model& model, const Setup& setup) {
  Plan plan;
  plan.precision = setup.precision;
  plan.effects = setup.effects;
  const std::size_t n_nodes = model.node_count();
  const std::size_t n_elems = model.element_count();
  plan.node_count = n_nodes;
  plan.element_count = n_elems;
  plan.voxel_size = model.grid.voxel_size;
  const double h = model.grid.voxel_size;
  const Effects& fx = setup.effects;

  // ---- validation ----
  if (n_elems == 0) bad("model", "the model has no elements");
  if (!(h > 0)) bad("model.grid.voxel_size", "voxel size must be positive");
  if (model.element_nodes.size() != n_elems) bad("model.element_nodes", "not one row per element");
  if (model.material_offsets.size() != n_elems + 1)
    bad("model.material_offsets", "expected element count + 1 entries");
  if (!(setup.duration >= 0)) bad("duration", "must be ≥ 0");
  if (!(setup.mass_scaling > 0)) bad("mass_scaling", "must be > 0");
  if (!(setup.mass_scaling <= kMaxMassScaling))
    bad("mass_scaling",
        fmt::format("{:.6g} is above {:.0e} (Δt × {:.0e}): inertia would be "
                    "meaningless; mass scaling is a modest factor",
                    setup.mass_scaling, kMaxMassScaling, std::sqrt(kMaxMassScaling)));
  if (!(setup.time_scaling > 0)) bad("time_scaling", "must be > 0");
  if (fx.damping && !(setup.damping_alpha >= 0)) bad("damping_alpha", "must be ≥ 0");
  if (!(setup.hourglass.kappa >= 0)) bad("hourglass.kappa", "must be ≥ 0");
  if (!(setup.time_step.safety_factor > 0 && setup.time_step.safety_factor <= 1))
    bad("time_step.safety_factor", "must be in (0, 1]");
  if (setup.energy_interval < 1) bad("energy_interval", "must be ≥ 1");
  if (!(setup.blowup_factor > 1)) bad("blowup_factor", "must be > 1");
  for (std::size_t m = 0; m < model.materials.size(); ++m) {
    const auto& mat = model.materials[m];
    if (!(mat.density > 0))
      throw ConfigError("", "model.materials.density",
                        "material '" + mat.name + "' has density ≤ 0")
          .at(static_cast<std::int64_t>(m));
    if (!(mat.shear_modulus >= 0 && mat.bulk_modulus >= 0))
      throw ConfigError("", "model.materials", "material '" + mat.name + "' has a negative modulus")
          .at(static_cast<std::int64_t>(m));
  }
  check_nodes(setup.rigid_nodes, n_nodes, "rigid_nodes");
  if (setup.jaw) {
    check_nodes(setup.jaw->nodes, n_nodes, "jaw.nodes");
    const auto& j = *setup.jaw;
    const auto length = [](const Vec3d& v) { return std::hypot(v[0], v[1], v[2]); };
    if (std::abs(length(j.axis) - 1) > 1e-6 || std::abs(length(j.forward) - 1) > 1e-6 ||
        std::abs(j.axis[0] * j.forward[0] + j.axis[1] * j.forward[1] + j.axis[2] * j.forward[2]) >
            1e-6)
      bad("jaw", "axis and forward must be orthogonal unit vectors");
  }
  if (setup.lip_contact) {
    for (const auto& [upper, lower] : setup.lip_contact->pairs) {
      check_nodes({upper, lower}, n_nodes, "lip_contact.pairs");
      if (upper == lower) bad("lip_contact.pairs", "a pair names one node twice");
    }
    const auto& up = setup.lip_contact->up;
    if (std::abs(std::hypot(up[0], up[1], up[2]) - 1) > 1e-6)
      bad("lip_contact.up", "must be a unit vector");
  }
  for (const auto& p : setup.sliding_planes) {
    check_nodes(p.nodes, n_nodes, "sliding_planes.nodes");
    if (!(std::hypot(p.normal[0], p.normal[1], p.normal[2]) > 0))
      bad("sliding_planes.normal", "normal must be non-zero");
  }
  for (const auto& v : setup.initial_velocities)
    check_nodes(v.nodes, n_nodes, "initial_velocities.nodes");
  if (fx.loads) {
    for (const auto& p : setup.prescribed) {
      check_nodes(p.nodes, n_nodes, "prescribed.nodes");
      if (!p.curve.valid()) bad("prescribed.curve", "times must be strictly increasing");
    }
    for (const auto& f : setup.forces) {
      check_nodes(f.nodes, n_nodes, "forces.nodes");
      if (f.nodes.empty()) bad("forces.nodes", "a force needs at least one node");
      if (!f.curve.valid()) bad("forces.curve", "times must be strictly increasing");
    }
  }
  if (fx.muscles) {
    if (setup.activation.size() > model.muscles.size())
      bad("activation",
          fmt::format("{} curves for {} muscles", setup.activation.size(), model.muscles.size()));
    for (const auto& c : setup.activation)
      if (!c.valid()) bad("activation", "times must be strictly increasing");
  }
  if (fx.sliding) {
    for (std::size_t i = 0; i < model.sliding.size(); ++i) {
      const auto& b = model.sliding[i];
      if (b.node < 0 || static_cast<std::size_t>(b.node) >= n_nodes)
        throw ConfigError("", "model.sliding.node", "node id out of range").at(std::int64_t(i));
      if (b.surface < 0 || static_cast<std::size_t>(b.surface) >= model.surfaces.size() ||
          model.surfaces[std::size_t(b.surface)].triangles.empty())
        throw ConfigError("", "model.sliding.surface", "no such surface with triangles")
            .at(std::int64_t(i));
    }
  }

  // ---- parameter rows ----
  const std::size_t n_mat = model.materials.size();
  auto hourglass_k = [&](double mu, double p_wave) {
    if (!fx.hourglass) return 0.0;
    const double m = setup.hourglass.modulus == HourglassModulus::shear ? 2 * mu : p_wave;
    return setup.hourglass.kappa * m * 3.0 * h / 16.0;
  };
  plan.parameters.resize(n_mat);
  for (std::size_t m = 0; m < n_mat; ++m) {
    const auto& mat = model.materials[m];
    ParameterRow& r = plan.parameters[m];
    r.mu = mat.shear_modulus;
    r.kappa = mat.bulk_modulus;
    r.p_wave = physics::p_wave_modulus(mat.shear_modulus, mat.bulk_modulus);
    r.density = mat.density * setup.mass_scaling;
    r.hourglass_k = hourglass_k(r.mu, r.p_wave);
  }
  plan.parameter_row.resize(n_elems);
  std::vector<char> multi(n_elems, 0);
  for (std::size_t e = 0; e < n_elems; ++e) {
    const auto b = model.material_offsets[e], en = model.material_offsets[e + 1];
    if (en <= b)
      throw ConfigError("", "model.material_offsets", "element has no material")
          .at(std::int64_t(e));
    if (en - b == 1 && model.material_fractions[std::size_t(b)] == 1.0) {
      plan.parameter_row[e] = model.material_ids[std::size_t(b)];
      continue;
    }
    ParameterRow r;
    for (auto k = b; k < en; ++k) {
      const auto id = model.material_ids[std::size_t(k)];
      if (id < 0 || std::size_t(id) >= n_mat)
        throw ConfigError("", "model.material_ids", "material id out of range").at(k);
      const double w = model.material_fractions[std::size_t(k)];
      const auto& mr = plan.parameters[std::size_t(id)];
      r.mu += w * mr.mu;
      r.kappa += w * mr.kappa;
      r.p_wave += w * mr.p_wave;
      r.density += w * mr.density;
    }
    r.hourglass_k = hourglass_k(r.mu, r.p_wave);
    plan.parameter_row[e] = static_cast<std::int32_t>(plan.parameters.size());
    plan.parameters.push_back(r);
    multi[e] = 1;
  }

  // ---- muscles ----
  std::vector<double> muscle_modulus;  // per element, for the time step
  std::vector<char> has_muscle(n_elems, 0);
  if (fx.muscles) {
    muscle_modulus.assign(n_elems, 0.0);
    for (std::size_t m = 0; m < model.muscles.size(); ++m) {
      const auto& mu = model.muscles[m];
      if (mu.fractions.size() != mu.elements.size() || mu.fibres.size() != mu.elements.size())
        throw ConfigError("", "model.muscles", "elements, fractions and fibres differ in length")
            .at(std::int64_t(m));
      const double a_max = setup.max_activation(m);
      const double fp_slope =
          physics::passive_fibre_max_slope(mu.passive_p1, mu.passive_p2, mu.passive_linear_stretch);
      for (std::size_t i = 0; i < mu.elements.size(); ++i) {
        const auto e = mu.elements[i];
        if (e < 0 || std::size_t(e) >= n_elems)
          throw ConfigError("", "model.muscles.elements", "element id out of range")
              .at(std::int64_t(i));
        has_muscle[std::size_t(e)] = 1;
        ++plan.muscle_entries;
        muscle_modulus[std::size_t(e)] += physics::muscle_tangent_modulus(
            mu.fractions[i], mu.reference_stress, mu.optimal_stretch, a_max, fp_slope);
      }
    }
  }

  // ---- collections ----
  const char* names[4] = {"single-material, no muscle", "multi-material, no muscle",
                          "single-material, with muscle", "multi-material, with muscle"};
  std::vector<ElementCollection> col(4);
  for (int c = 0; c < 4; ++c) {
    col[std::size_t(c)].name = names[c];
    col[std::size_t(c)].multi_material = (c & 1) != 0;
    col[std::size_t(c)].muscle = (c & 2) != 0;
  }
  for (std::size_t e = 0; e < n_elems; ++e)
    col[std::size_t((multi[e] ? 1 : 0) + (has_muscle[e] ? 2 : 0))].elements.push_back(Index(e));
  for (auto& c : col)
    if (!c.elements.empty()) plan.collections.push_back(std::move(c));

  // ---- time step ----
  double dt_crit = std::numeric_limits<double>::infinity();
  double max_modulus = 0;
  for (std::size_t e = 0; e < n_elems; ++e) {
    const auto& r = plan.parameters[std::size_t(plan.parameter_row[e])];
    double modulus = fx.elasticity ? r.p_wave : 0.0;
    if (fx.muscles) modulus += muscle_modulus[e];
    if (!fx.elasticity && fx.hourglass) modulus += r.hourglass_k / h;  // only resistance left
    max_modulus = std::max(max_modulus, modulus);
    const double dte = physics::critical_time_step(h, modulus, r.density);
    if (dte < dt_crit) {
      dt_crit = dte;
      plan.dt_critical_element = Index(e);
    }
  }
  plan.dt_critical = dt_crit;
  // A modulus so large that h/c underflows to 0 (a muscle reference stress of 1e308 Pa in a
  // damaged model) was reported as the scene's duration being "inf steps at Δt = 0 s"; one that
  // makes waves faster than kMaxWaveSpeed (a muscle's passive p1 of 1e30: 4e18 steps for 10 ms)
  // blamed the duration too. Both are the model's values.
  if (!(dt_crit > 0) || h / dt_crit > kMaxWaveSpeed) {
    const auto e = std::size_t(plan.dt_critical_element);
    const auto& r = plan.parameters[std::size_t(plan.parameter_row[e])];
    throw ConfigError(
        "", "model",
        fmt::format("the stable step h/c is {:.3g} s at element {} (wave modulus {:.3g} Pa: "
                    "{:.3g} Pa of its materials, {:.3g} Pa of its muscle fibres; density {:.3g} "
                    "kg/m^3; waves at {:.3g} m/s, faster than in any solid: at most {:.0f} m/s "
                    "here): a material's stiffness, a muscle's reference stress or its passive "
                    "curve (p1, p2) is out of range, or the model is damaged (sinew-inspect "
                    "--element {} shows it)",
                    dt_crit, e,
                    (fx.elasticity ? r.p_wave : 0.0) + (fx.muscles ? muscle_modulus[e] : 0.0),
                    fx.elasticity ? r.p_wave : 0.0, fx.muscles ? muscle_modulus[e] : 0.0, r.density,
                    h / dt_crit, kMaxWaveSpeed, e));
  }
  const auto& ts = setup.time_step;
  const double allowed = ts.safety_factor * dt_crit;
  const bool finite = dt_crit < 1e29;
  std::string where = finite ? fmt::format("element {} (h = {:.4g} m, c = {:.4g} m/s)",
                                           plan.dt_critical_element, h, h / dt_crit)
                             : std::string("no stiffness in the model");
  switch (ts.policy) {
    case TimeStepPolicy::automatic:
      if (!finite) explain_no_step(model, plan, dt_crit, max_modulus);
      plan.dt = allowed;
      plan.dt_reason = fmt::format("automatic: {} × Δt_crit {:.6g} s (= h/c at {})",
                                   ts.safety_factor, dt_crit, where);
      break;
    case TimeStepPolicy::user:
      if (!(ts.user_dt > 0)) bad("time_step.user_dt", "must be > 0");
      if (ts.user_dt > allowed)
        bad("time_step.user_dt",
            fmt::format(
                "Δt = {:.6g} s is above the stable estimate {} × {:.6g} s = {:.6g} s set by "
                "{}; lower it or force it",
                ts.user_dt, ts.safety_factor, dt_crit, allowed, where));
      plan.dt = ts.user_dt;
      plan.dt_reason = fmt::format("user: {:.6g} s (≤ {} × Δt_crit {:.6g} s at {})", ts.user_dt,
                                   ts.safety_factor, dt_crit, where);
      break;
    case TimeStepPolicy::forced:
      if (!(ts.user_dt > 0)) bad("time_step.user_dt", "must be > 0");
      plan.dt = ts.user_dt;
      plan.dt_reason = fmt::format("forced: {:.6g} s = {:.4g} × Δt_crit {:.6g} s at {}", ts.user_dt,
                                   ts.user_dt / dt_crit, dt_crit, where);
      if (ts.user_dt > allowed)
        plan.warnings.push_back(fmt::format(
            "forced Δt {:.6g} s is {:.3g} × the critical estimate h/c: the run may go unstable",
            ts.user_dt, ts.user_dt / dt_crit));
      break;
  }
  // h/c is the Courant length, not the limit: one-point cubes with lumped mass are stable up to
  // about 0.85 h/c at ν = 0.49 (time_step.hpp), and the accuracy study saw 0.9 diverge.
  if (finite && ts.policy != TimeStepPolicy::forced && plan.dt > kSafeCourantShare * dt_crit)
    plan.warnings.push_back(fmt::format(
        "Δt = {:.3g} × h/c is above {} × h/c, beyond which one-point hexahedra can go unstable "
        "(≈ 0.85 h/c at ν = 0.49, less with hourglass stiffness or compression); the run stops "
        "with a clear message if it does",
        plan.dt / dt_crit, kSafeCourantShare));
  // Counted in double first: a huge duration (or time_scaling) must be refused, not wrap around
  // to a negative int64 and "complete" after 0 steps. 2^53 is where step indices stop being
  // exact in the double time arithmetic; run_limits.hpp sets the (overridable) sane limit.
  const double steps = setup.duration > 0 ? std::ceil(setup.duration / plan.dt - 1e-9) : 0.0;
  if (!(steps <= 0x1p53)) {
    bad(setup.time_scaling != 1 ? "time_scaling" : "duration",
        fmt::format(
            "duration {:.6g} s{} at Δt = {:.3g} s is {:.3g} steps, more than a run can count",
            setup.duration / setup.time_scaling,
            setup.time_scaling != 1 ? fmt::format(" × time_scaling {:.6g}", setup.time_scaling)
                                    : std::string(),
            plan.dt, steps));
  }
  plan.steps = static_cast<std::int64_t>(steps);
  if (setup.mass_scaling != 1)
    plan.warnings.push_back(fmt::format(
        "mass scaling × {}: densities scaled, Δt × {:.4g}; inertia is wrong by this factor",
        setup.mass_scaling, std::sqrt(setup.mass_scaling)));
  if (setup.time_scaling != 1)
    plan.warnings.push_back(fmt::format(
        "time scaling × {}: curves are read at t/{}; the motion is {} × slower than the scene's",
        setup.time_scaling, setup.time_scaling, setup.time_scaling));
  if (fx.hourglass && setup.hourglass.modulus == HourglassModulus::p_wave)
    plan.warnings.push_back(
        "hourglass modulus λ + 2μ locks bending as ν -> 0.5 (physics-notes §3)");

  // ---- sliding counts ----
  if (fx.sliding) {
    plan.sliding_nodes = model.sliding.size();
    std::vector<char> used(model.surfaces.size(), 0);
    for (const auto& b : model.sliding) used[std::size_t(b.surface)] = 1;
    for (std::size_t s = 0; s < used.size(); ++s)
      if (used[s]) plan.sliding_triangles += model.surfaces[s].triangles.size();
  }

  // ---- stages ----
  std::size_t muscle_elems = 0;
  for (const auto& c : plan.collections)
    if (c.muscle) muscle_elems += c.elements.size();
  std::string terms;
  if (fx.elasticity) terms += "neo-Hookean";
  if (fx.hourglass)
    terms += std::string(terms.empty() ? "" : " + ") +
             fmt::format("hourglass (κ = {}, {})", setup.hourglass.kappa,
                         modulus_name(setup.hourglass.modulus));
  if (fx.muscles) terms += std::string(terms.empty() ? "" : " + ") + "muscle fibres";
  if (terms.empty()) terms = "nothing (no force-producing effect)";
  plan.stages.push_back(
      {"element forces",
       fmt::format(
           "{} on {} elements in {} collections ({})", terms, n_elems, plan.collections.size(),
           fx.muscles ? fmt::format("{} with muscle", muscle_elems) : std::string("muscles off"))});
  plan.stages.push_back(
      {"gather", fmt::format("per node, fixed (element, corner) order, {} nodes", n_nodes)});
  std::size_t force_nodes = 0, prescribed_nodes = 0, plane_nodes = 0;
  for (const auto& f : setup.forces) force_nodes += f.nodes.size();
  for (const auto& p : setup.prescribed) prescribed_nodes += p.nodes.size();
  for (const auto& p : setup.sliding_planes) plane_nodes += p.nodes.size();
  if (fx.loads && force_nodes)
    plan.stages.push_back(
        {"nodal forces", fmt::format("{} sets, {} nodes", setup.forces.size(), force_nodes)});
  if (fx.gravity)
    plan.stages.push_back(
        {"gravity",
         fmt::format("g = ({}, {}, {}) m/s², lumped Σ w ρ g V0/8 per element node, unscaled ρ",
                     setup.gravity[0], setup.gravity[1], setup.gravity[2])});
  plan.stages.push_back({"central-difference update",
                         fx.damping ? fmt::format("damped, α = {} 1/s", setup.damping_alpha)
                                    : std::string("undamped")});
  if (fx.sliding && plan.sliding_nodes)
    plan.stages.push_back(
        {"sliding surfaces", fmt::format("{} nodes on {} triangles, uniform grid, warm start",
                                         plan.sliding_nodes, plan.sliding_triangles)});
  if (plane_nodes)
    plan.stages.push_back(
        {"sliding planes",
         fmt::format("{} planes, {} nodes", setup.sliding_planes.size(), plane_nodes)});
  if (setup.lip_contact)
    plan.stages.push_back(
        {"lip contact", fmt::format("{} pairs across the cut between the lips: the upper node "
                                    "kept above the lower one",
                                    setup.lip_contact->pairs.size())});
  if (fx.loads && prescribed_nodes)
    plan.stages.push_back(
        {"prescribed displacements",
         fmt::format("{} sets, {} nodes", setup.prescribed.size(), prescribed_nodes)});
  if (setup.jaw)
    plan.stages.push_back({"jaw", fmt::format("{} nodes moved as one rigid body (opening, "
                                              "protrusion, lateral shift from the scene's curves)",
                                              setup.jaw->nodes.size())});
  if (!setup.rigid_nodes.empty())
    plan.stages.push_back({"rigid nodes", fmt::format("{} nodes", setup.rigid_nodes.size())});
  plan.stages.push_back(
      {"checks", fmt::format("NaN/Inf and J ≤ 0 every step; energies and blow-up every {} steps",
                             setup.energy_interval)});

  // ---- arrays ----
  const std::size_t t = setup.precision == Precision::float32 ? 4 : 8;
  const char* tn = precision_name(setup.precision);
  const std::size_t n = n_nodes, e = n_elems;
  auto add = [&](std::string name, std::string shape, std::size_t bytes) {
    plan.arrays.push_back({std::move(name), std::move(shape), bytes});
  };
  add("element nodes", "E × 8 int32", e * 8 * 4);
  add("element parameter row", "E int32", e * 4);
  add("parameter table (μ, κ, k_HG)", fmt::format("{} rows × 3 {}", plan.parameters.size(), tn),
      plan.parameters.size() * 3 * t);
  add("dominant material (output)", "E int32", e * 4);
  add("element forces", fmt::format("E × 8 × 3 {}", tn), e * 24 * t);
  add("node incidence", "(N+1) int64 + 8E int32", (n + 1) * 8 + e * 8 * 4);
  add("displacement u(n), u(n−1), u(n+1)", fmt::format("3 × N × 3 {}", tn), 9 * n * t);
  add("internal force", fmt::format("N × 3 {}", tn), 3 * n * t);
  add("inverse lumped mass", fmt::format("N {}", tn), n * t);
  add("rest positions", fmt::format("N × 3 {}", tn), 3 * n * t);
  for (const auto& c : plan.collections)
    add("collection: " + c.name, "int32 element ids", c.elements.size() * 4);
  if (fx.gravity) add("gravity force", fmt::format("N × 3 {}", tn), 3 * n * t);
  if (fx.muscles) {
    add("muscle offsets", "(E+1) int64", (e + 1) * 8);
    add("muscle entries", fmt::format("{} × (int32 + 4 {})", plan.muscle_entries, tn),
        plan.muscle_entries * (4 + 4 * t));
    add("muscle parameters + activation",
        fmt::format("{} muscles × 6 {}", model.muscles.size(), tn), model.muscles.size() * 6 * t);
  }
  if (fx.sliding && plan.sliding_nodes) {
    add("sliding bindings", fmt::format("{} × (2 int32 + {})", plan.sliding_nodes, tn),
        plan.sliding_nodes * (8 + t));
    add("sliding triangles + normals",
        fmt::format("{} × (3 int32 + 3 {})", plan.sliding_triangles, tn),
        plan.sliding_triangles * (12 + 3 * t));
    add("sliding grid (≈ 1 cell per triangle)", "cells int32 offsets + entries",
        plan.sliding_triangles * 4 * 4);
  }
  if (fx.loads && (prescribed_nodes + force_nodes))
    add("load node lists", "int32", (prescribed_nodes + force_nodes) * 4);
  if (plane_nodes) add("sliding planes", "int32 node ids", plane_nodes * 4);
  if (!setup.rigid_nodes.empty()) add("rigid nodes", "int32", setup.rigid_nodes.size() * 4);
  if (setup.jaw)
    add("jaw nodes + their captures", fmt::format("int32 + 3 {}", tn),
        setup.jaw->nodes.size() * (4 + 3 * t));
  if (setup.lip_contact)
    add("lip contact entries", fmt::format("int32 partner + {} share", tn),
        2 * setup.lip_contact->pairs.size() * (4 + t));
  return plan;
}

std::string Plan::explain() const {
  std::ostringstream o;
  o << fmt::format("Plan: {} nodes, {} elements (h = {:.4g} m), precision {}\n", node_count,
                   element_count, voxel_size, precision_name(precision));
  auto onoff = [](bool b) { return b ? "on" : "off"; };
  o << fmt::format(
      "Effects: elasticity {}, hourglass {}, damping {}, gravity {}, muscles {}, sliding {}, loads "
      "{}, contact {}\n",
      onoff(effects.elasticity), onoff(effects.hourglass), onoff(effects.damping),
      onoff(effects.gravity), onoff(effects.muscles), onoff(effects.sliding), onoff(effects.loads),
      onoff(effects.contact));
  o << "Stages (each step, in order):\n";
  for (std::size_t i = 0; i < stages.size(); ++i)
    o << fmt::format("  {}. {}: {}\n", i + 1, stages[i].name, stages[i].detail);
  o << "Element collections:\n";
  for (const auto& c : collections)
    o << fmt::format("  {:<30} {:>10} elements\n", c.name, c.elements.size());
  o << fmt::format(
      "  parameter rows: {} (materials shared by single-material elements + one per "
      "multi-material element)\n",
      parameters.size());
  if (!effects.muscles) o << "  muscles off: no muscle arrays, no muscle work\n";
  if (!effects.sliding) o << "  sliding off: no sliding arrays, no closest-point searches\n";
  o << "Memory:\n";
  for (const auto& a : arrays)
    o << fmt::format("  {:<40} {:<34} {:>12}\n", a.name, a.shape, human_bytes(a.bytes));
  o << fmt::format("  {:<40} {:<34} {:>12}\n", "total", "", human_bytes(total_bytes()));
  o << fmt::format("Time step: Δt = {:.6g} s, {} steps\n  {}\n", dt, steps, dt_reason);
  for (const auto& w : warnings) o << "Warning: " << w << "\n";
  return o.str();
}

}  // namespace sinew::simulator
