#pragma once
// Shared helpers of the simulator physics tests. Tests take a BackendFactory so the same test code
// runs on every backend listed in a test file's kBackends (a backend that cannot run here, e.g.
// CUDA without a device, makes its cases skip: backend_missing).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <functional>
#include <memory>
#include <ostream>
#include <string>
#include <tuple>
#include <vector>

#include "sinew/formats/box_model.hpp"
#include "sinew/formats/model.hpp"
#include "sinew/simulator/engine/backend.hpp"
#include "sinew/simulator/engine/cpu_engine.hpp"
#include "sinew/simulator/engine/cuda_backend.hpp"
#include "sinew/simulator/engine/setup.hpp"

namespace sinew::simulator::testing {

using BackendFactory = std::function<std::unique_ptr<Backend>(const formats::Model&, const Setup&)>;

struct NamedBackend {
  std::string name;
  BackendFactory make;
  // Null: the backend always runs. Otherwise, when it returns false, every case on this backend
  // skips with the message `missing` (e.g. the CUDA backend without a device).
  bool (*available)() = nullptr;
  const char* missing = "";
};
// GoogleTest prints a parameter with this (the backend's name) instead of its raw bytes.
inline void PrintTo(const NamedBackend& b, std::ostream* os) {
  *os << b.name;
}
inline bool backend_missing(const NamedBackend& b) {
  return b.available != nullptr && !b.available();
}
inline const NamedBackend& backend_of(const NamedBackend& b) {
  return b;
}
template <typename... Rest>
const NamedBackend& backend_of(const std::tuple<NamedBackend, Rest...>& p) {
  return std::get<0>(p);
}

// A test parametrised on a backend (alone or first in a tuple): skips where it cannot run.
template <typename Param>
class BackendTest : public ::testing::TestWithParam<Param> {
 protected:
  void SetUp() override {
    const NamedBackend& b = backend_of(this->GetParam());
    if (backend_missing(b)) GTEST_SKIP() << b.missing;
  }
};
inline std::string backend_name(const ::testing::TestParamInfo<NamedBackend>& info) {
  return info.param.name;
}

// Every backend built here: the CPU, and the CUDA backend where it is compiled (its cases skip with
// "no CUDA device" where there is none, e.g. in CI, so they show as skipped): once with its default
// assembly (automatic: gather on most test models) and once with tiled assembly forced.
inline const std::vector<NamedBackend>& every_backend() {
  static const std::vector<NamedBackend> backends = {
      {"cpu", &make_cpu_backend, nullptr, ""},
#ifdef SINEW_CUDA_ENABLED
      {"cuda", [](const formats::Model& m, const Setup& s) { return make_cuda_backend(m, s); },
       &cuda_device_available, "no CUDA device"},
      {"cuda_tiled",
       [](const formats::Model& m, const Setup& s) {
         CudaOptions o;
         o.assembly = ForceAssembly::tiled;
         return make_cuda_backend(m, s, o);
       },
       &cuda_device_available, "no CUDA device"},
#endif
  };
  return backends;
}

// A TLED neo-Hookean material from μ and ν.
inline formats::Material neo_hookean(double mu, double nu, double density = 1000.0,
                                     const std::string& name = "tissue") {
  return formats::make_neo_hookean_material_from_shear(name, mu, nu, density);
}

// A block of nx × ny × nz cubes of side h with one material.
inline formats::Model block(int nx, int ny, int nz, double h, const formats::Material& mat) {
  formats::BoxSpec spec;
  spec.dims = {nx, ny, nz};
  spec.voxel_size = h;
  spec.materials = {mat};
  spec.created = "2026-01-01T00:00:00Z";
  return formats::make_box_model(spec);
}

// Nodes whose lattice coordinate along `axis` equals `value`.
inline std::vector<Index> nodes_at(const formats::Model& m, int axis, int value) {
  std::vector<Index> out;
  for (std::size_t n = 0; n < m.node_count(); ++n)
    if (m.node_lattice[n][std::size_t(axis)] == value) out.push_back(Index(n));
  return out;
}
// The bending case of physics-notes §3: a cantilever of 20 × 2 × 2 cubes of side h, clamped at
// x = 0 (rigid nodes), a small tip load P spread over its end face (nodal forces; tip deflection
// ≈ 3e-5 L, small strain), damped critically for the first bending mode (ω1 = 1.875² √(EI/(ρA))/L²).
// reference: Euler–Bernoulli P L³/(3EI) plus Timoshenko shear P L/(κ_s μ A), κ_s = 5/6, m.
struct Cantilever {
  formats::Model model;
  Setup setup;
  std::vector<Index> tip_nodes;
  double reference = 0;  // m, tip deflection
  double omega1 = 0;     // 1/s, first bending mode
};
inline Cantilever make_cantilever(double mu, double nu, double rho, double h,
                                  HourglassModulus modulus) {
  const int nx = 20, nt = 2;
  const auto mat = neo_hookean(mu, nu, rho);
  Cantilever c;
  c.model = block(nx, nt, nt, h, mat);
  Setup& s = c.setup;
  s.effects.damping = true;
  s.effects.loads = true;
  s.hourglass.modulus = modulus;
  s.rigid_nodes = nodes_at(c.model, 0, 0);
  NodalForce f;
  f.nodes = nodes_at(c.model, 0, nx);
  const double l = nx * h, t = nt * h, e = mat.youngs_modulus, inertia = t * t * t * t / 12;
  const double p = 1e-4 * e * inertia / (l * l);
  f.total = {0, 0, -p};
  s.forces.push_back(f);
  c.tip_nodes = f.nodes;
  c.omega1 = 1.875 * 1.875 * std::sqrt(e * inertia / (rho * t * t)) / (l * l);
  s.damping_alpha = 2 * c.omega1;
  c.reference = p * l * l * l / (3 * e * inertia) + p * l / (mu * t * t * 5.0 / 6);
  return c;
}
// Mean downward displacement of the given nodes, m.
inline double mean_drop(const Backend& b, const std::vector<Index>& nodes) {
  const auto u = b.displacements();
  double tip = 0;
  for (auto n : nodes) tip -= u[3 * std::size_t(n) + 2];
  return tip / double(nodes.size());
}

inline std::vector<Index> nodes_if(const formats::Model& m,
                                   const std::function<bool(const formats::Lattice&)>& pred) {
  std::vector<Index> out;
  for (std::size_t n = 0; n < m.node_count(); ++n)
    if (pred(m.node_lattice[n])) out.push_back(Index(n));
  return out;
}

inline std::array<double, 3> node_u(const std::vector<double>& u, Index n) {
  return {u[3 * std::size_t(n)], u[3 * std::size_t(n) + 1], u[3 * std::size_t(n) + 2]};
}

// Steps in batches until the kinetic energy falls below `ke_tol` (J) or max_steps pass.
// Returns the final kinetic energy.
inline double relax(Backend& b, std::int64_t max_steps, double ke_tol, std::int64_t batch = 200) {
  double ke = b.energies().kinetic;
  for (std::int64_t s = 0; s < max_steps; s += batch) {
    b.step(batch);
    ke = b.energies().kinetic;
    if (ke < ke_tol && s > batch) break;
  }
  return ke;
}

// A uniaxial-style Setup: damped, loads on, user-chosen safety factor.
inline Setup static_setup(double alpha) {
  Setup s;
  s.effects.damping = true;
  s.effects.loads = true;
  s.damping_alpha = alpha;
  s.time_step.safety_factor = 0.5;
  return s;
}

// Lowest-mode-ish critical damping for a block of side L: α = 2 ω with ω = π c / (2 L),
// c = sqrt(μ/ρ) (shear wave speed; the slowest waves).
inline double critical_alpha(double mu, double rho, double length) {
  return 2.0 * M_PI * std::sqrt(mu / rho) / (2.0 * length);
}

}  // namespace sinew::simulator::testing
