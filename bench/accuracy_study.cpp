// Accuracy versus time (docs/accuracy-vs-time.md): problems with known answers run over a grid of
// settings on one backend; one CSV row per point (settings, steps, wall time, error).
//
//   convergence  cantilever under its own weight, elements per thickness n = 1 … 16, ν = 0.3 and
//                0.49: tip deflection against the Richardson extrapolation of the sequence (and
//                against beam theory)
//   nu_sweep     the same cantilever at ν = 0.3 … 0.4999 with each hourglass modulus and κ: tip
//                deflection against beam theory (near-incompressible bending, locking)
//   forehead     a 16 × 8 × 2 mm forehead-like patch (layers muscle / hypodermis / dermis /
//                stratum corneum, two frontalis muscles, sliding on a curved skull) raising the brow
//                over 20 ms: skin (top surface) displacement at 40 ms against a fine-voxel reference
//   knobs        one knob at a time: precision, time-step safety factor, mass scaling, time
//                scaling, hourglass κ, sliding on/off, and the cost of each effect
//
// Usage: accuracy_study [--quick | --full] [--device cpu|cuda] [--threads N] [--csv FILE]
//                       [--problems convergence,nu_sweep,forehead,knobs] [--provenance TEXT]
//        accuracy_study --write-models DIR [--full]   (the models of the sweep files in
//                       bench/accuracy/, as model files; nothing is run)
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "accuracy_study_measures.hpp"
#include "sinew/common/error.hpp"
#include "sinew/common/math.hpp"
#include "sinew/common/tool.hpp"
#include "sinew/formats/box_model.hpp"
#include "sinew/formats/model_file.hpp"
#include "sinew/simulator/engine/backend.hpp"
#include "sinew/simulator/engine/cpu_engine.hpp"
#include "sinew/simulator/engine/cuda_backend.hpp"
#include "sliding_height_field.hpp"

using namespace sinew;
using namespace sinew::simulator;
using accuracy::FaceField;

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}
const double kNaN = std::nan("");

// ---- options, CSV ------------------------------------------------------------------------------
struct Options {
  bool full = false;
  std::string device = "cpu";
  int threads = 0;
  std::string csv = "accuracy_study.csv";
  std::set<std::string> problems{"convergence", "nu_sweep", "forehead", "knobs"};
  std::string provenance;
  std::string command;
  std::string write_models;  // --write-models DIR: write the models and stop
};

struct Row {
  std::string problem, knob, value;
  std::string precision = "double";
  double h = kNaN;   // m, voxel side
  int per_edge = 0;  // elements through the thickness
  std::size_t elements = 0, nodes = 0;
  double nu = kNaN, dt = kNaN, safety = 0.5, mass_scaling = 1, time_scaling = 1, kappa = 0.075;
  std::string modulus = "shear", effects;
  std::int64_t steps = 0;
  double sim_time = kNaN;  // s of scene time
  double wall = kNaN;      // s, the step loop
  double error = kNaN, error_rms = kNaN;
  std::string error_measure;
  double value_measured = kNaN;   // the raw quantity (tip deflection m, or skin |u| max m)
  double hourglass_ratio = kNaN;  // hourglass / strain energy at the end
  std::string status = "ok";
};

class Csv {
 public:
  Csv(const Options& o, const std::string& device_name) : out_(o.csv) {
    if (!out_) throw IoError(o.csv, "", "cannot write the CSV");
    char host[256] = {};
    gethostname(host, sizeof host - 1);
    std::time_t now = std::time(nullptr);
    char date[64];
    std::strftime(date, sizeof date, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
    out_ << "# accuracy_study " << (o.full ? "--full" : "--quick") << " on " << o.device << "\n";
    out_ << "# date: " << date << "\n# host: " << host << "\n# machine: " << device_name << "\n";
    out_ << "# command: " << o.command << "\n";
    if (!o.provenance.empty()) out_ << "# " << o.provenance << "\n";
    out_ << "problem,knob,value,device,precision,h_mm,per_edge,elements,nodes,nu,dt_s,"
            "safety_factor,mass_scaling,time_scaling,kappa,hourglass_modulus,effects,steps,"
            "sim_time_s,wall_s,wall_per_step_us,wall_per_sim_s,error,error_rms,error_measure,"
            "measured,hourglass_ratio,status\n";
    device_ = o.device;
  }
  void write(const Row& r) {
    auto num = [](double v) {
      if (!std::isfinite(v)) return std::string();
      char b[64];
      std::snprintf(b, sizeof b, "%.6g", v);
      return std::string(b);
    };
    const double per_step = r.steps > 0 ? r.wall / double(r.steps) : kNaN;
    const double per_sim = r.sim_time > 0 ? r.wall / r.sim_time : kNaN;
    out_ << r.problem << ',' << r.knob << ',' << r.value << ',' << device_ << ',' << r.precision
         << ',' << num(r.h * 1e3) << ',' << r.per_edge << ',' << r.elements << ',' << r.nodes << ','
         << num(r.nu) << ',' << num(r.dt) << ',' << num(r.safety) << ',' << num(r.mass_scaling)
         << ',' << num(r.time_scaling) << ',' << num(r.kappa) << ',' << r.modulus << ','
         << r.effects << ',' << r.steps << ',' << num(r.sim_time) << ',' << num(r.wall) << ','
         << num(per_step * 1e6) << ',' << num(per_sim) << ',' << num(r.error) << ','
         << num(r.error_rms) << ',' << r.error_measure << ',' << num(r.value_measured) << ','
         << num(r.hourglass_ratio) << ',' << r.status << '\n';
    out_.flush();
    std::printf(
        "%-11s %-13s %-10s h %6.3f mm  %8zu el  dt %9.3g s  %8lld steps  %8.2f s  error %9.3g"
        "  %s\n",
        r.problem.c_str(), r.knob.c_str(), r.value.c_str(), r.h * 1e3, r.elements, r.dt,
        (long long)r.steps, r.wall, r.error, r.status.c_str());
    std::fflush(stdout);
  }

 private:
  std::ofstream out_;
  std::string device_;
};

std::unique_ptr<Backend> make_backend(const Options& o, const formats::Model& m, Setup s) {
  if (o.device == "cuda") return make_cuda_backend(m, s);
  s.threads = o.threads;
  return make_cpu_backend(m, s);
}

std::vector<Index> nodes_where(const formats::Model& m, int axis, int value) {
  std::vector<Index> out;
  for (std::size_t n = 0; n < m.node_count(); ++n)
    if (m.node_lattice[n][std::size_t(axis)] == value) out.push_back(Index(n));
  return out;
}

std::string effects_text(const Setup& s) {
  std::string t;
  auto add = [&](bool on, const char* name) {
    if (!on) return;
    if (!t.empty()) t += '+';
    t += name;
  };
  add(s.effects.elasticity, "elasticity");
  add(s.effects.hourglass, "hourglass");
  add(s.effects.damping, "damping");
  add(s.effects.gravity, "gravity");
  add(s.effects.muscles, "muscles");
  add(s.effects.sliding, "sliding");
  add(s.effects.loads, "loads");
  add(s.effects.contact, "contact");
  return t;
}

void fill_settings(Row& r, const Setup& s) {
  r.precision = s.precision == Precision::float32 ? "float" : "double";
  r.safety = s.time_step.safety_factor;
  r.mass_scaling = s.mass_scaling;
  r.time_scaling = s.time_scaling;
  r.kappa = s.effects.hourglass ? s.hourglass.kappa : 0;
  r.modulus = s.hourglass.modulus == HourglassModulus::shear ? "shear" : "p_wave";
  r.effects = effects_text(s);
}

// An InstabilityError stopped the run: the row keeps the step where it was detected.
void unstable(Row& r, const Backend* b, Clock::time_point t0) {
  r.status = "unstable";
  if (!b) return;
  r.wall = seconds_since(t0);
  r.steps = b->step_index();
  r.status = "unstable_at_step_" + std::to_string(r.steps);
}

// ---- cantilever under its own weight ----------------------------------------------------------
// L = 10 mm, square section t = 2 mm, n elements through the thickness (5n along), clamped at
// x = 0 (rigid nodes), gravity −z, μ = 150 kPa, ρ = 1000 kg/m³: tip deflection ≈ 0.9 % of L at
// ν = 0.3 (small strain, so beam theory applies).
constexpr double kBeamL = 10e-3, kBeamT = 2e-3, kBeamMu = 1.5e5, kBeamRho = 1000, kG = 9.81;

struct BeamSpec {
  int n = 2;
  double nu = 0.3;
  Precision precision = Precision::float64;
  bool hourglass = true;
  Hourglass hg;
  double safety = 0.5;
};

struct BeamResult {
  Row row;
  double tip = kNaN;  // m, mean downward deflection of the end face
};

// Euler–Bernoulli plus Timoshenko shear for a uniform load q = ρ g A on a clamped beam:
//   w = q L⁴ / (8 E I) + q L² / (2 k_s μ A),  k_s = 10 (1 + ν) / (12 + 11 ν) (Cowper 1966, square)
double beam_theory_tip(double nu) {
  const double e = 2 * kBeamMu * (1 + nu), a = kBeamT * kBeamT, i = std::pow(kBeamT, 4) / 12;
  const double q = kBeamRho * kG * a, ks = 10 * (1 + nu) / (12 + 11 * nu);
  return q * std::pow(kBeamL, 4) / (8 * e * i) + q * kBeamL * kBeamL / (2 * ks * kBeamMu * a);
}

// The beam's model: n elements through the thickness, 5n along. `clamped_face`: the clamp as the
// model's rigid nodes (the x_min face), for the model files of --write-models; the runs here set
// it in their Setup.
formats::Model beam_model(int n, double nu, bool clamped_face = false) {
  formats::BoxSpec spec;
  spec.dims = {5 * n, n, n};
  spec.voxel_size = kBeamT / n;
  spec.materials = {
      formats::make_neo_hookean_material("beam", 2 * kBeamMu * (1 + nu), nu, kBeamRho)};
  if (clamped_face) spec.rigid_faces = {"x_min"};
  spec.created = "2026-01-01T00:00:00Z";
  return formats::make_box_model(spec);
}

BeamResult run_beam(const Options& o, const BeamSpec& c) {
  const int n = c.n, nx = 5 * n;
  const double h = kBeamT / n;
  const formats::Model model = beam_model(n, c.nu);
  Setup s;
  s.precision = c.precision;
  s.effects.gravity = true;
  s.effects.damping = true;
  s.effects.hourglass = c.hourglass;
  s.hourglass = c.hg;
  s.gravity = {0, 0, -kG};
  s.rigid_nodes = nodes_where(model, 0, 0);
  s.time_step.safety_factor = c.safety;
  // Critical damping of the first bending mode, ω1 = 1.875² sqrt(E I / (ρ A)) / L²: every
  // under-damped mode then decays at least as fast as exp(−ω1 t).
  const double e = 2 * kBeamMu * (1 + c.nu);
  const double omega1 =
      1.875 * 1.875 * std::sqrt(e * kBeamT * kBeamT / 12 / kBeamRho) / (kBeamL * kBeamL);
  s.damping_alpha = 2 * omega1;
  BeamResult out;
  Row& r = out.row;
  fill_settings(r, s);
  r.h = h;
  r.per_edge = n;
  r.nu = c.nu;
  r.elements = model.element_count();
  r.nodes = model.node_count();
  const auto tip_nodes = nodes_where(model, 0, nx);
  std::unique_ptr<Backend> b;
  auto t0 = Clock::now();
  try {
    b = make_backend(o, model, s);
    r.dt = b->dt();
    const std::int64_t batch = std::max<std::int64_t>(20, std::llround(0.5 / (omega1 * r.dt)));
    const std::int64_t max_steps = std::llround(80 / (omega1 * r.dt));
    // Float round-off leaves ~1e−7 relative noise on the tip; 1e−6 per batch still settles it.
    const double tol = c.precision == Precision::float32 ? 1e-6 : 1e-7;
    double prev = 0, tip = 0;
    bool converged = false;
    t0 = Clock::now();
    while (b->step_index() < max_steps) {
      b->step(batch);
      const auto u = b->displacements();
      tip = 0;
      for (auto nd : tip_nodes) tip -= u[3 * std::size_t(nd) + 2];
      tip /= double(tip_nodes.size());
      if (std::abs(tip - prev) < tol * std::abs(tip)) {
        converged = true;
        break;
      }
      prev = tip;
    }
    r.wall = seconds_since(t0);
    r.steps = b->step_index();
    r.sim_time = b->time();
    const auto en = b->energies();
    r.hourglass_ratio = en.strain != 0 ? en.hourglass / std::abs(en.strain) : kNaN;
    out.tip = tip;
    r.value_measured = tip;
    if (!converged) r.status = "not_converged";
  } catch (const InstabilityError&) {
    unstable(r, b.get(), t0);
  }
  return out;
}

// ---- forehead-like patch -----------------------------------------------------------------------
// 16 × 8 × 2 mm, voxel side h = 2 mm / nz. Layers from the bottom (as make_forehead_model):
// muscle tissue to 0.5 mm, hypodermis to 1 mm, dermis to 1.98 mm, stratum corneum (20 µm). Two
// frontalis muscles (fibres +y) under x ∈ [2, 6] and [10, 14] mm, y ∈ [0, 6] mm, 0.5 mm thick: the
// elements of the bottom ceil(0.5 mm / h) layers with muscle fraction 0.5 mm / (layers · h), so
// the muscle volume is the same at every h. Bottom nodes slide on a curved skull
// z = −0.125 mm − (x − 8 mm)² / (2 · 32 mm) (1.125 mm below the bottom at the sides), sampled every
// 0.25 mm for every h. The edge y = 8 mm is rigid (the scalp); y = 0 is the brow.
constexpr double kPatchX = 16e-3, kPatchY = 8e-3, kPatchZ = 2e-3;
constexpr double kRampTime = 0.02, kPatchDuration = 0.04, kPeakActivation = 0.1, kPatchAlpha = 150;

bench::HeightField skull_surface() {
  const double s = 0.25e-3, xc = 0.5 * kPatchX, radius = 32e-3;
  const int sx = int(std::lround((kPatchX + 2e-3) / s)),
            sy = int(std::lround((kPatchY + 2e-3) / s));
  return bench::make_height_field("skull", -1e-3, -1e-3, s, sx, sy, [&](double x, double) {
    return -0.125e-3 - (x - xc) * (x - xc) / (2 * radius);
  });
}

// `rigid_scalp`: the edge y = 8 mm as the model's rigid nodes (the y_max face), for the model files
// of --write-models; the runs here set it in their Setup.
formats::Model forehead_patch(double h, bool rigid_scalp = false) {
  const int nx = int(std::lround(kPatchX / h)), ny = int(std::lround(kPatchY / h)),
            nz = int(std::lround(kPatchZ / h));
  auto tissue = [](const char* name, double e) {
    return formats::make_neo_hookean_material(name, e, 0.49, 11000);
  };
  formats::BoxSpec spec;
  spec.dims = {nx, ny, nz};
  spec.voxel_size = h;
  spec.materials = {tissue("muscle", 0.5e6), tissue("hypodermis", 34e3), tissue("dermis", 81.4e3),
                    tissue("stratum_corneum", 48e6)};
  spec.layer_boundaries = {0.5e-3, 1.0e-3, 1.98e-3};
  if (rigid_scalp) spec.rigid_faces = {"y_max"};
  const int layers = int(std::ceil(0.5e-3 / h - 1e-9));
  for (int m = 0; m < 2; ++m) {
    formats::BoxMuscleSpec ms;
    ms.name = m == 0 ? "frontalis_left" : "frontalis_right";
    ms.material = 0;
    const double xa = m == 0 ? 2e-3 : 10e-3;
    ms.element_min = {int(std::lround(xa / h)), 0, 0};
    ms.element_max = {int(std::lround((xa + 4e-3) / h)), int(std::lround(6e-3 / h)), layers};
    ms.fibre = {0, 1, 0};
    ms.fraction = 0.5e-3 / (layers * h);
    spec.muscles.push_back(ms);
  }
  spec.created = "2026-01-01T00:00:00Z";
  formats::Model model = formats::make_box_model(spec);
  bench::bind_bottom_to_height_field(model, skull_surface(), 8);
  // A node both rigid and sliding (the scalp edge's bottom row) is rigid: the model format allows
  // one role per node.
  if (rigid_scalp) {
    std::erase_if(model.sliding, [&](const formats::SlidingBinding& b) {
      return std::binary_search(model.rigid_nodes.begin(), model.rigid_nodes.end(), b.node);
    });
  }
  return model;
}

struct PatchSpec {
  double h = 0.5e-3;
  Precision precision = Precision::float64;
  double safety = 0.5, mass_scaling = 1, time_scaling = 1;
  bool hourglass = true;
  Hourglass hg;
  bool muscles = true, sliding = true, damping = true;
  bool rigid_base = false;           // sliding off: the bottom nodes held instead
  double duration = kPatchDuration;  // s of scene time
  std::int64_t fixed_steps = -1;     // > 0: run exactly this many steps (cost only)
};

struct PatchResult {
  Row row;
  std::vector<std::array<double, 3>> skin;  // top-surface displacement at the 1 mm sample grid
};

// Sample points: the top surface on a 1 mm grid (17 × 9).
std::vector<std::array<double, 2>> skin_points() {
  std::vector<std::array<double, 2>> p;
  for (int j = 0; j <= 8; ++j)
    for (int i = 0; i <= 16; ++i) p.push_back({i * 1e-3, j * 1e-3});
  return p;
}

PatchResult run_patch(const Options& o, const PatchSpec& c) {
  const formats::Model model = forehead_patch(c.h);
  Setup s;
  s.precision = c.precision;
  s.effects.hourglass = c.hourglass;
  s.hourglass = c.hg;
  s.effects.muscles = c.muscles;
  s.effects.sliding = c.sliding;
  s.effects.damping = c.damping;
  s.damping_alpha = kPatchAlpha;
  s.mass_scaling = c.mass_scaling;
  s.time_scaling = c.time_scaling;
  s.time_step.safety_factor = c.safety;
  const Curve act = Curve::ramp(kRampTime, kPeakActivation);
  if (c.muscles) s.activation = {act, act};
  const int ny = int(std::lround(kPatchY / c.h)), nz = int(std::lround(kPatchZ / c.h)),
            nx = int(std::lround(kPatchX / c.h));
  s.rigid_nodes = nodes_where(model, 1, ny);
  if (c.rigid_base) {
    for (auto n : nodes_where(model, 2, 0)) s.rigid_nodes.push_back(n);
    std::sort(s.rigid_nodes.begin(), s.rigid_nodes.end());
    s.rigid_nodes.erase(std::unique(s.rigid_nodes.begin(), s.rigid_nodes.end()),
                        s.rigid_nodes.end());
  }
  s.duration = c.duration * c.time_scaling;
  PatchResult out;
  Row& r = out.row;
  fill_settings(r, s);
  if (c.rigid_base) r.effects += "(base_rigid)";
  r.h = c.h;
  r.per_edge = nz;
  r.nu = 0.49;
  r.elements = model.element_count();
  r.nodes = model.node_count();
  std::unique_ptr<Backend> b;
  auto t0 = Clock::now();
  try {
    b = make_backend(o, model, s);
    r.dt = b->dt();
    const std::int64_t steps =
        c.fixed_steps > 0 ? c.fixed_steps : std::int64_t(std::ceil(s.duration / r.dt - 1e-9));
    t0 = Clock::now();
    b->step(steps);
    const auto u = b->displacements();  // the copy back is part of the cost of a result
    r.wall = seconds_since(t0);
    r.steps = steps;
    r.sim_time = b->time() / c.time_scaling;
    const auto en = b->energies();
    // |strain|: the active muscle term of the strain energy may make it negative.
    r.hourglass_ratio = en.strain != 0 ? en.hourglass / std::abs(en.strain) : kNaN;
    FaceField f;
    f.nx = nx;
    f.ny = ny;
    f.h = c.h;
    f.values.resize(std::size_t((nx + 1) * (ny + 1)));
    for (auto n : nodes_where(model, 2, nz)) {
      const auto& l = model.node_lattice[std::size_t(n)];
      f.values[std::size_t(l[0] + (nx + 1) * l[1])] = {
          u[3 * std::size_t(n)], u[3 * std::size_t(n) + 1], u[3 * std::size_t(n) + 2]};
    }
    double umax = 0;
    for (const auto& p : skin_points()) {
      out.skin.push_back(accuracy::sample(f, p[0], p[1]));
      const auto& v = out.skin.back();
      umax = std::max(umax, std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]));
    }
    r.value_measured = umax;
  } catch (const InstabilityError&) {
    unstable(r, b.get(), t0);
  }
  return out;
}

void set_error(Row& r, const std::vector<std::array<double, 3>>& u,
               const std::vector<std::array<double, 3>>& ref, const std::string& measure) {
  r.error_measure = measure;
  if (r.status != "ok" || u.size() != ref.size()) return;
  const auto e = accuracy::field_error(u, ref);
  r.error = e.max_rel;
  r.error_rms = e.rms_rel;
}

// ---- the problems ------------------------------------------------------------------------------
struct Context {
  Options o;
  Csv* csv = nullptr;
  // Richardson-extrapolated tip deflections from the convergence problem, by ν.
  std::map<double, double> beam_reference;
};

void convergence(Context& ctx) {
  const std::vector<int> ns =
      ctx.o.full ? std::vector<int>{1, 2, 3, 4, 6, 8, 12, 16} : std::vector<int>{1, 2, 3, 4, 6, 8};
  for (double nu : {0.3, 0.49}) {
    std::vector<BeamResult> res;
    for (int n : ns) {
      // Quick: ν = 0.49 stops at n = 6 (its n = 8 costs 3.5× the ν = 0.3 one: c_d/c_E is 3.6×).
      if (!ctx.o.full && nu > 0.4 && n > 6) continue;
      BeamSpec c;
      c.n = n;
      c.nu = nu;
      res.push_back(run_beam(ctx.o, c));
    }
    // Reference: Richardson extrapolation from the three finest meshes.
    const std::size_t k = res.size();
    accuracy::Extrapolation ex;
    if (k >= 3)
      ex = accuracy::richardson(res[k - 3].row.h, res[k - 3].tip, res[k - 2].row.h, res[k - 2].tip,
                                res[k - 1].row.h, res[k - 1].tip);
    const double ref = ex.ok ? ex.value : res.back().tip;
    ctx.beam_reference[nu] = ref;
    const double theory = beam_theory_tip(nu);
    std::printf(
        "convergence ν = %.2f: Richardson reference %.6g m (order %.3f, %s), beam theory "
        "%.6g m (reference / theory %.4f)\n",
        nu, ref, ex.order, ex.ok ? "ok" : "not monotone: finest value used", theory, ref / theory);
    for (auto& r : res) {
      r.row.problem = "convergence";
      r.row.knob = "per_edge";
      r.row.value = std::to_string(r.row.per_edge);
      r.row.error = std::abs(r.tip - ref) / std::abs(ref);
      r.row.error_rms = std::abs(r.tip - theory) / theory;
      r.row.error_measure = "tip_vs_richardson(rms=vs_beam_theory)";
      ctx.csv->write(r.row);
    }
    Row summary;
    summary.problem = "convergence";
    summary.knob = "reference";
    summary.value = ex.ok ? "richardson" : "finest";
    summary.nu = nu;
    summary.value_measured = ref;
    summary.error = ex.order;  // observed order of the extrapolation
    summary.error_rms = ref / theory - 1;
    summary.error_measure = "order(rms=reference/beam_theory-1)";
    summary.status = ex.ok ? "ok" : "not_monotone";
    ctx.csv->write(summary);
  }
}

void nu_sweep(Context& ctx) {
  const std::vector<double> nus = {0.3, 0.4, 0.45, 0.49, 0.495, 0.499, 0.4999};
  const std::vector<int> ns = ctx.o.full ? std::vector<int>{2, 4} : std::vector<int>{2};
  const std::vector<double> kappas =
      ctx.o.full ? std::vector<double>{0.05, 0.075, 0.15} : std::vector<double>{0.075};
  for (int n : ns)
    for (auto mod : {HourglassModulus::shear, HourglassModulus::p_wave})
      for (double kappa : kappas)
        for (double nu : nus) {
          BeamSpec c;
          c.n = n;
          c.nu = nu;
          c.hg.modulus = mod;
          c.hg.kappa = kappa;
          auto r = run_beam(ctx.o, c);
          r.row.problem = "nu_sweep";
          r.row.knob = "nu";
          char v[32];
          std::snprintf(v, sizeof v, "%g", nu);
          r.row.value = v;
          const double theory = beam_theory_tip(nu);
          r.row.error = r.tip / theory - 1;  // signed: negative = too stiff (locking)
          r.row.error_measure = "tip/beam_theory-1";
          ctx.csv->write(r.row);
        }
}

// The forehead reference and the h sweep.
struct PatchReference {
  double h = 0;
  std::vector<std::array<double, 3>> skin;
  double wall = 0;
};

PatchReference patch_reference(Context& ctx) {
  PatchSpec c;
  c.h = ctx.o.full ? 0.125e-3 : 1e-3 / 3;
  auto r = run_patch(ctx.o, c);
  r.row.problem = "forehead";
  r.row.knob = "reference";
  r.row.value = "h";
  r.row.error_measure = "reference";
  ctx.csv->write(r.row);
  if (r.row.status != "ok") throw std::runtime_error("the forehead reference run failed");
  return {c.h, r.skin, r.row.wall};
}

const char* kSkinMeasure = "skin_max_vs_ref(rms)";

void forehead(Context& ctx, const PatchReference& ref) {
  std::vector<double> hs = {1e-3, 2e-3 / 3, 0.5e-3, 0.4e-3};
  if (ctx.o.full) {
    hs.push_back(1e-3 / 3);
    hs.push_back(0.25e-3);
  }
  for (Precision p : {Precision::float64, Precision::float32}) {
    if (p == Precision::float32 && !ctx.o.full) continue;  // quick: float only in the knobs
    for (double h : hs) {
      PatchSpec c;
      c.h = h;
      c.precision = p;
      auto r = run_patch(ctx.o, c);
      r.row.problem = "forehead";
      r.row.knob = "h";
      char v[32];
      std::snprintf(v, sizeof v, "%.4g", h * 1e3);
      r.row.value = v;
      set_error(r.row, r.skin, ref.skin, kSkinMeasure);
      ctx.csv->write(r.row);
    }
  }
}

void knobs(Context& ctx, const PatchReference& ref) {
  auto emit = [&](PatchResult r, const std::string& knob, const std::string& value,
                  const std::vector<std::array<double, 3>>& against, const std::string& measure) {
    r.row.problem = "knobs";
    r.row.knob = knob;
    r.row.value = value;
    set_error(r.row, r.skin, against, measure);
    ctx.csv->write(r.row);
    return r;
  };
  auto fmt = [](double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%g", v);
    return std::string(b);
  };
  // Quick: h = 2/3 mm (864 elements), full: 1/3 mm (6,912 elements; the full reference is 0.125 mm).
  const double h = ctx.o.full ? 1e-3 / 3 : 2e-3 / 3;

  // The default settings at this h: the baseline every knob is compared with too.
  PatchSpec base;
  base.h = h;
  const PatchResult b0 = run_patch(ctx.o, base);
  emit(b0, "baseline", "default", ref.skin, kSkinMeasure);

  // Precision.
  {
    PatchSpec c = base;
    c.precision = Precision::float32;
    const PatchResult r = run_patch(ctx.o, c);
    emit(r, "precision", "float", ref.skin, kSkinMeasure);
    emit(r, "precision_vs_double", "float", b0.skin, "skin_max_vs_double(rms)");
  }
  // Time-step safety factor: against the reference and against the same h at 0.3 (the temporal
  // part of the error alone).
  {
    PatchSpec c = base;
    c.safety = 0.3;
    const PatchResult t03 = run_patch(ctx.o, c);
    emit(t03, "safety_factor", "0.3", ref.skin, kSkinMeasure);
    for (double f : {0.5, 0.7, 0.8, 0.9, 0.95}) {
      c.safety = f;
      const PatchResult r = run_patch(ctx.o, c);
      emit(r, "safety_factor", fmt(f), ref.skin, kSkinMeasure);
      emit(r, "safety_factor_vs_0.3", fmt(f), t03.skin, "skin_max_vs_safety_0.3(rms)");
    }
  }
  // Mass scaling: against the unscaled run at the same h (what the scaling alone changes).
  for (double m : {2.0, 5.0, 10.0, 25.0, 100.0}) {
    PatchSpec c = base;
    c.mass_scaling = m;
    const PatchResult r = run_patch(ctx.o, c);
    emit(r, "mass_scaling", fmt(m), b0.skin, "skin_max_vs_unscaled(rms)");
    emit(r, "mass_scaling_vs_ref", fmt(m), ref.skin, kSkinMeasure);  // for the Pareto front
  }
  // Combinations for a preview: safety factor 0.8 with mass scaling, against the reference and the
  // baseline.
  for (double m : {10.0, 100.0}) {
    PatchSpec c = base;
    c.safety = 0.8;
    c.mass_scaling = m;
    const PatchResult r = run_patch(ctx.o, c);
    emit(r, "preview_safety0.8_mass", fmt(m), ref.skin, kSkinMeasure);
    emit(r, "preview_vs_baseline", fmt(m), b0.skin, "skin_max_vs_baseline(rms)");
  }
  // Time scaling: the same motion s times slower, against the unscaled run and against the
  // quasi-static answer (activation held, relaxed for 0.15 s of scene time: under-damped
  // modes have decayed by exp(−α t / 2) = 6e−5 since the ramp ended; the CSV's time-scaled rows
  // show how close the slower ones have come).
  {
    PatchSpec st = base;
    st.duration = 0.15;
    const PatchResult stat = run_patch(ctx.o, st);
    emit(stat, "static", "0.15 s", b0.skin, "skin_max_static_vs_default(rms)");
    emit(b0, "time_scaling_vs_static", "1", stat.skin, "skin_max_vs_static(rms)");
    const std::vector<double> scalings =
        ctx.o.full ? std::vector<double>{2, 4, 8} : std::vector<double>{2};
    for (double s : scalings) {
      PatchSpec c = base;
      c.time_scaling = s;
      const PatchResult r = run_patch(ctx.o, c);
      emit(r, "time_scaling", fmt(s), b0.skin, "skin_max_vs_unscaled(rms)");
      emit(r, "time_scaling_vs_static", fmt(s), stat.skin, "skin_max_vs_static(rms)");
    }
    for (double m : {4.0, 25.0, 100.0}) {
      PatchSpec c = base;
      c.mass_scaling = m;
      emit(run_patch(ctx.o, c), "mass_scaling_vs_static", fmt(m), stat.skin,
           "skin_max_vs_static(rms)");
    }
  }
  // Hourglass κ (0: hourglass control off).
  for (double k : {0.0, 0.025, 0.05, 0.1, 0.15}) {
    PatchSpec c = base;
    c.hourglass = k > 0;
    c.hg.kappa = k > 0 ? k : 0.075;
    const PatchResult r = run_patch(ctx.o, c);
    emit(r, "kappa", fmt(k), ref.skin, kSkinMeasure);
    emit(r, "kappa_vs_default", fmt(k), b0.skin, "skin_max_vs_kappa_0.075(rms)");
  }
  {
    PatchSpec c = base;
    c.hg.modulus = HourglassModulus::p_wave;
    emit(run_patch(ctx.o, c), "hourglass_modulus", "p_wave", ref.skin, kSkinMeasure);
  }
  // Sliding off: the skull-side nodes held instead.
  {
    PatchSpec c = base;
    c.sliding = false;
    c.rigid_base = true;
    emit(run_patch(ctx.o, c), "sliding", "off(base_rigid)", ref.skin, kSkinMeasure);
  }
  // Hourglass κ on the cantilever (bending through hourglass modes), against its reference.
  if (ctx.beam_reference.count(0.49)) {
    for (double k : {0.0, 0.025, 0.05, 0.075, 0.1, 0.15}) {
      BeamSpec c;
      c.n = 2;
      c.nu = 0.49;
      c.hourglass = k > 0;
      c.hg.kappa = k > 0 ? k : 0.075;
      auto r = run_beam(ctx.o, c);
      r.row.problem = "knobs";
      r.row.knob = "kappa_beam";
      r.row.value = fmt(k);
      r.row.error = r.tip / ctx.beam_reference[0.49] - 1;
      r.row.error_measure = "tip/richardson-1";
      ctx.csv->write(r.row);
    }
    for (Precision p : {Precision::float64, Precision::float32}) {
      BeamSpec c;
      c.n = 4;
      c.nu = 0.49;
      c.precision = p;
      auto r = run_beam(ctx.o, c);
      r.row.problem = "knobs";
      r.row.knob = "precision_beam";
      r.row.value = p == Precision::float32 ? "float" : "double";
      r.row.error = std::abs(r.tip / ctx.beam_reference[0.49] - 1);
      r.row.error_measure = "|tip/richardson-1|";
      ctx.csv->write(r.row);
    }
  }
  // Cost of each effect: time per step over a fixed number of steps (no error).
  struct Variant {
    const char* name;
    bool hourglass, muscles, sliding, damping;
  };
  const Variant variants[] = {{"elasticity", false, false, false, false},
                              {"+hourglass", true, false, false, false},
                              {"+muscles", true, true, false, false},
                              {"+sliding", true, true, true, false},
                              {"+damping(all)", true, true, true, true}};
  for (Precision p : {Precision::float64, Precision::float32})
    for (const auto& v : variants) {
      PatchSpec c = base;
      c.h = ctx.o.full ? 0.25e-3 : 0.4e-3;  // enough elements that the per-step overhead is small
      c.precision = p;
      c.hourglass = v.hourglass;
      c.muscles = v.muscles;
      c.sliding = v.sliding;
      c.damping = v.damping;
      c.fixed_steps = ctx.o.full ? 2000 : 300;
      auto r = run_patch(ctx.o, c);
      r.row.problem = "effects";
      r.row.knob = "effects";
      r.row.value = v.name;
      r.row.error_measure = "none";
      ctx.csv->write(r.row);
    }
}

// --write-models DIR: the study's models as model files for the sweep files of bench/accuracy/
// (README there): the cantilevers cantilever_n<n>_nu<nu>.h5 (clamped face as rigid nodes) and the
// forehead patches forehead_patch_<h in um>um.h5 (scalp edge as rigid nodes, sliding skull).
// --full adds the full study's finer patches (0.25 and 0.125 mm: 131,072 elements).
void write_models(const Options& o, const std::string& dir) {
  std::filesystem::create_directories(dir);
  const auto write = [&](const formats::Model& m, const std::string& name) {
    const auto path = (std::filesystem::path(dir) / name).string();
    formats::write_model(m, path);
    std::printf("wrote %s: %zu elements\n", path.c_str(), m.element_count());
  };
  char name[96];
  std::set<std::pair<int, double>> beams;
  for (double nu : {0.3, 0.49})
    for (int n : {1, 2, 3, 4, 6, 8}) beams.insert({n, nu});
  if (o.full)
    for (double nu : {0.3, 0.49})
      for (int n : {12, 16}) beams.insert({n, nu});
  for (double nu : {0.3, 0.4, 0.45, 0.49, 0.495, 0.499, 0.4999}) {
    beams.insert({2, nu});
    if (o.full) beams.insert({4, nu});
  }
  for (const auto& [n, nu] : beams) {
    std::snprintf(name, sizeof name, "cantilever_n%d_nu%g.h5", n, nu);
    write(beam_model(n, nu, true), name);
  }
  std::vector<double> hs = {1e-3, 2e-3 / 3, 0.5e-3, 0.4e-3, 1e-3 / 3};
  if (o.full) hs.insert(hs.end(), {0.25e-3, 0.125e-3});
  for (double h : hs) {
    std::snprintf(name, sizeof name, "forehead_patch_%dum.h5", int(std::lround(h * 1e6)));
    write(forehead_patch(h, true), name);
  }
}

int run(int argc, char** argv) {
  Options o;
  for (int i = 0; i < argc; ++i) o.command += (i ? " " : "") + std::string(argv[i]);
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw ConfigError("", a, "needs a value");
      return argv[++i];
    };
    if (a == "--quick")
      o.full = false;
    else if (a == "--full")
      o.full = true;
    else if (a == "--device")
      o.device = value();
    else if (a == "--threads")
      o.threads = std::atoi(value().c_str());
    else if (a == "--csv")
      o.csv = value();
    else if (a == "--provenance")
      o.provenance = value();
    else if (a == "--write-models")
      o.write_models = value();
    else if (a == "--problems") {
      o.problems.clear();
      std::stringstream ss(value());
      std::string p;
      while (std::getline(ss, p, ','))
        if (!p.empty()) o.problems.insert(p);
    } else {
      std::fprintf(stderr,
                   "usage: accuracy_study [--quick|--full] [--device cpu|cuda] [--threads N] "
                   "[--csv FILE] [--problems convergence,nu_sweep,forehead,knobs] "
                   "[--provenance TEXT] [--write-models DIR]\n");
      return 2;
    }
  }
  if (!o.write_models.empty()) {
    write_models(o, o.write_models);
    return 0;
  }
  if (o.device != "cpu" && o.device != "cuda") throw ConfigError("", "--device", "cpu or cuda");
  std::string machine;
  if (o.device == "cuda") {
    if (!cuda_device_available())
      throw ConfigError("", "--device", "cuda: no CUDA device (or a build without CUDA)");
    machine = cuda_device_name();
  } else {
    std::ifstream cpu("/proc/cpuinfo");
    std::string line;
    while (std::getline(cpu, line))
      if (line.rfind("model name", 0) == 0) {
        machine = line.substr(line.find(':') + 2);
        break;
      }
    machine += ", " + std::to_string(sysconf(_SC_NPROCESSORS_ONLN)) + " cores, threads " +
               (o.threads > 0 ? std::to_string(o.threads) : std::string("all"));
  }
  Csv csv(o, machine);
  Context ctx{o, &csv, {}};
  const auto t0 = Clock::now();
  const bool need_beam_ref = o.problems.count("convergence") || o.problems.count("knobs");
  if (need_beam_ref) convergence(ctx);
  if (o.problems.count("nu_sweep")) nu_sweep(ctx);
  if (o.problems.count("forehead") || o.problems.count("knobs")) {
    const PatchReference ref = patch_reference(ctx);
    if (o.problems.count("forehead")) forehead(ctx, ref);
    if (o.problems.count("knobs")) knobs(ctx, ref);
  }
  std::printf("accuracy_study: done in %.1f s, CSV %s\n", seconds_since(t0), o.csv.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return sinew::tool::run("accuracy_study", [&] { return run(argc, argv); });
}
