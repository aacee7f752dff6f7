// sinew.Simulation: a run's engine (load_run, the path sinew-simulate and sinew-live share) that
// Python steps, reads and steers. Without `steering` its plan, time step and every step are
// sinew-simulate's, so stepping it to the end gives sinew-simulate's displacements bit for bit;
// with it the time step is planned for any activation in [0, 1] (as sinew-live plans it) so
// set_activation may go past the scene's peaks.
//
// Threads: the GIL is released while stepping (other Python threads run meanwhile), and a
// simulation serves one call at a time: a second thread's call while it steps raises
// RuntimeError rather than reading a state being written. Ctrl-C stops step() at a step
// boundary (Python's signals are checked between the engine's batches, Backend::
// preferred_step_count: 64 steps on the CPU).
#include <pybind11/stl.h>

#include <fmt/format.h>

#include <mutex>

#include "bindings.hpp"
#include "sinew/common/error.hpp"
#include "sinew/simulator/engine/cuda_backend.hpp"
#include "sinew/simulator/run/run_setup.hpp"

namespace sinew::python {
namespace {

class Simulation {
 public:
  Simulation(const PyScene& scene, const std::string& device, const py::object& precision,
             int threads, bool steering, int force_slots) {
    if (threads < 0) throw ConfigError("", "threads", "must be ≥ 0 (0: OpenMP's default)");
    if (force_slots < 0 || force_slots > 64)
      throw ConfigError("", "force_slots", "must be in [0, 64]");
    simulator::RunOptions o;
    o.scene_path = scene_name(scene);
    o.scene_text = scene.text;
    o.scene_directory = scene.directory;
    o.device = device;
    o.precision = precision_from(precision);
    o.threads = threads;
    o.quiet = true;
    run_ = without_gil([&] {
      return simulator::load_run(o, [&](simulator::Setup& setup) {
        setup.activation_overrides = steering && setup.effects.muscles;
        setup.force_slots = setup.effects.loads ? force_slots : 0;
      });
    });
    model_ = std::make_shared<PyModel>(PyModel{run_.model, run_.scene.model_path, ""});
    for (const auto& mu : run_.model->muscles) muscles_.push_back(mu.name);
    steering_ = steering;
  }

  // This call's hold on the simulation, refused while another thread steps.
  std::unique_lock<std::mutex> exclusive() {
    std::unique_lock lock(mutex_, std::try_to_lock);
    if (!lock.owns_lock())
      throw std::runtime_error("this Simulation is busy in another thread (stepping)");
    return lock;
  }

  // The backend, for one call, refused while another thread steps.
  template <typename F>
  auto with_backend(F&& f) {
    const auto lock = exclusive();
    return f(backend());
  }

  simulator::Backend& backend() {
    if (!run_.backend) throw std::runtime_error("this Simulation is closed");
    return *run_.backend;
  }

  // Frees the engine (its GPU memory) now rather than when Python collects the object.
  void close() {
    const auto lock = exclusive();
    run_.backend.reset();
  }

  void step(std::int64_t n) {
    if (n < 0) throw ConfigError("", "n", fmt::format("cannot step backwards ({})", n));
    const auto lock = exclusive();
    auto& backend = this->backend();
    const std::int64_t batch = std::max<std::int64_t>(1, backend.preferred_step_count());
    for (std::int64_t done = 0; done < n;) {
      const std::int64_t k = std::min(batch, n - done);
      without_gil([&] { backend.step(k); });
      done += k;
      if (done < n && PyErr_CheckSignals() != 0) throw py::error_already_set();
    }
  }

  std::size_t muscle(const std::string& name) const {
    for (std::size_t m = 0; m < muscles_.size(); ++m)
      if (muscles_[m] == name) return m;
    std::string list;
    for (const auto& s : muscles_) list += (list.empty() ? "" : ", ") + s;
    throw ConfigError("", "muscle",
                      fmt::format("no muscle '{}' in the model (it has: {})", name,
                                  list.empty() ? "none" : list));
  }

  simulator::LoadedRun run_;
  std::shared_ptr<PyModel> model_;
  std::vector<std::string> muscles_;
  bool steering_ = false;
  std::mutex mutex_;
};

py::array_t<double> nodes_by_3(std::vector<double>&& v) {
  const auto n = static_cast<py::ssize_t>(v.size() / 3);
  return take(std::move(v), {n, 3});
}

py::dict energies_dict(const simulator::Energies& e) {
  py::dict d;
  d["step"] = e.step;
  d["time"] = e.time;
  d["kinetic"] = e.kinetic;
  d["strain"] = e.strain;
  d["elastic"] = e.elastic;
  d["hourglass"] = e.hourglass;
  d["external_work"] = e.external_work;
  return d;
}

}  // namespace

void bind_simulation(py::module_& m) {
  m.def("cuda_available", &simulator::cuda_device_available,
        "Whether this build has the CUDA backend and a CUDA device is visible to the process "
        "(device='auto' then runs on it).");
  py::class_<simulator::State>(m, "State", R"doc(
A simulation's whole dynamic state (Simulation.state()): restoring it into a simulation of the
same scene and model continues bit for bit. Arrays are copies.
)doc")
      .def_readonly("step", &simulator::State::step, "n: u holds u(n)")
      .def_readonly("time", &simulator::State::time, "s of engine time, n · Δt")
      .def_readonly("dt", &simulator::State::dt, "s, the Δt of the run that made it")
      .def_property_readonly(
          "u", [](const simulator::State& s) { return nodes_by_3(std::vector<double>(s.u)); },
          "N × 3, m: u(n)")
      .def_property_readonly(
          "u_prev",
          [](const simulator::State& s) { return nodes_by_3(std::vector<double>(s.u_prev)); },
          "N × 3, m: u(n − 1)")
      .def("__repr__", [](const simulator::State& s) {
        return fmt::format("<sinew.State step {}, t = {:g} s>", s.step, s.time);
      });

  py::class_<Simulation>(m, "_Simulation", py::dynamic_attr())
      .def(py::init<const PyScene&, const std::string&, const py::object&, int, bool, int>(),
           py::arg("scene"), py::arg("device"), py::arg("precision"), py::arg("threads"),
           py::arg("steering"), py::arg("force_slots"))
      .def("close", &Simulation::close,
           "Frees the engine (and its GPU memory) now; any later call raises RuntimeError. "
           "`with sinew.Simulation(...) as sim:` closes it at the end of the block.")
      .def("step", &Simulation::step, py::arg("n") = 1,
           "Advances n steps of Δt (the GIL released; Ctrl-C raises KeyboardInterrupt at a step "
           "boundary). Raises sinew.UnstableError, the state then at the step where the problem "
           "was found.")
      .def_property_readonly(
          "step_index",
          [](Simulation& s) { return s.with_backend([](auto& b) { return b.step_index(); }); },
          "n: the steps done (the state holds u(n)).")
      .def_property_readonly(
          "time",
          [](Simulation& s) {
            return s.with_backend(
                [&](auto& b) { return b.time() / s.run_.resolved.setup.time_scaling; });
          },
          "s of scene time: n · Δt / time_scaling (results' frame times).")
      .def_property_readonly(
          "dt", [](Simulation& s) { return s.backend().dt(); },
          "Δt, s of simulated time (the plan's: docs/physics.md; run_summary.json's dt_s).")
      .def_property_readonly("time_scaling",
                             [](Simulation& s) { return s.run_.resolved.setup.time_scaling; })
      .def_property_readonly(
          "steps_planned", [](Simulation& s) { return s.run_.summary.steps_planned; },
          "The steps the scene's duration takes: ceil(duration × time_scaling / Δt).")
      .def_property_readonly(
          "device", [](Simulation& s) { return s.run_.summary.device; },
          "e.g. 'cpu (OpenMP, 2 threads)' or 'cuda (NVIDIA H100 80GB HBM3)'.")
      .def_property_readonly("precision", [](Simulation& s) { return s.run_.summary.precision; })
      .def_property_readonly("effects", [](Simulation& s) { return s.run_.resolved.effects; })
      .def_property_readonly(
          "warnings", [](Simulation& s) { return s.run_.summary.warnings; },
          "The set-up's warnings (what the model defines and the scene leaves out, ...).")
      .def_property_readonly("steering", [](Simulation& s) { return s.steering_; })
      .def_property_readonly(
          "muscles", [](Simulation& s) { return s.muscles_; }, "The model's muscle names.")
      .def_property_readonly(
          "model", [](Simulation& s) { return s.model_; },
          "The sinew.Model simulated (shared with the engine, not copied).")
      .def(
          "displacements",
          [](Simulation& s, const py::object& nodes) {
            if (nodes.is_none())
              return s.with_backend([](auto& b) {
                return nodes_by_3(without_gil([&] { return b.displacements(); }));
              });
            const auto ids = node_ids(nodes, "nodes", s.run_.model->node_count());
            return s.with_backend([&](auto& b) { return nodes_by_3(b.displacements(ids)); });
          },
          py::arg("nodes") = py::none(),
          "u(n), m: N × 3, or of the listed node ids only (k × 3, gathered on the device). A "
          "new array each call.")
      .def(
          "velocities",
          [](Simulation& s) {
            return s.with_backend([](auto& b) { return nodes_by_3(b.velocities()); });
          },
          "N × 3, m/s: (u(n) − u(n−1)) / Δt.")
      .def(
          "internal_forces",
          [](Simulation& s) {
            return s.with_backend([](auto& b) { return nodes_by_3(b.internal_forces()); });
          },
          "N × 3, N: the internal nodal forces at u(n).")
      .def(
          "reaction",
          [](Simulation& s, const py::object& nodes) {
            const auto ids = node_ids(nodes, "nodes", s.run_.model->node_count());
            return s.with_backend([&](auto& b) { return b.reaction(ids); });
          },
          py::arg("nodes"),
          "N: Σ over the nodes of (internal force − external load): at rest, the force the "
          "supports exert there (a reaction probe's value).")
      .def(
          "energies",
          [](Simulation& s) {
            return s.with_backend([](auto& b) { return energies_dict(b.energies()); });
          },
          "J: kinetic, strain, elastic, hourglass, external_work at step n (with step, time).")
      .def(
          "element_fields",
          [](Simulation& s) {
            auto f = s.with_backend([](auto& b) { return b.element_fields(); });
            const auto e = static_cast<py::ssize_t>(f.jacobian.size());
            std::vector<double> cauchy(6 * f.cauchy.size());
            for (std::size_t i = 0; i < f.cauchy.size(); ++i)
              for (int k = 0; k < 6; ++k) cauchy[6 * i + k] = f.cauchy[i][k];
            py::dict d;
            d["J"] = take(std::move(f.jacobian), {e});
            d["von_mises"] = take(std::move(f.von_mises), {e});
            d["cauchy"] = take(std::move(cauchy), {e, 6});
            d["energy_density"] = take(std::move(f.energy_density), {e});
            d["material"] = take(std::move(f.material), {e});
            return d;
          },
          "Per element at u(n): J, von_mises (Pa), cauchy (E × 6, Pa, xx yy zz yz xz xy), "
          "energy_density (J/m³), material (the dominant one).")
      .def(
          "set_activation",
          [](Simulation& s, const std::string& name, std::optional<double> a) {
            const auto m = s.muscle(name);
            s.with_backend([&](auto& b) {
              b.set_activation_override(m, a);
              return 0;
            });
          },
          py::arg("muscle"), py::arg("activation"),
          "Steers a muscle from the next step: its activation ramps over 30 ms of simulated "
          "time to `activation` in [0, 1] (None: back to its curve). Without steering=True it "
          "may not exceed the scene's peak for it (the time step was planned for that).")
      .def(
          "activation",
          [](Simulation& s, const std::string& name) {
            const auto m = s.muscle(name);
            return s.with_backend([&](auto& b) { return b.activation_override(m); });
          },
          py::arg("muscle"), "The muscle's steered target, or None when its curve drives it.")
      .def_property_readonly(
          "force_slots", [](Simulation& s) { return s.backend().force_slot_count(); },
          "How many set_force slots it has (0 unless the scene's effects include loads).")
      .def(
          "set_force",
          [](Simulation& s, const py::object& nodes, const py::object& force, std::size_t slot) {
            const auto ids = node_ids(nodes, "nodes", s.run_.model->node_count());
            const auto f = finite_doubles(force, "force", 0);
            if (f.size() != 3)
              throw ConfigError(
                  "", "force", fmt::format("expected 3 components (N per node), got {}", f.size()));
            s.with_backend([&](auto& b) {
              if (b.force_slot_count() == 0)
                throw ConfigError(
                    "", "force",
                    "this simulation has no force slots: its scene's effects leave out "
                    "`loads` (add it to push nodes from Python)");
              b.set_force_slot(slot, ids, {f[0], f[1], f[2]});
              return 0;
            });
          },
          py::arg("nodes"), py::arg("force"), py::arg("slot") = 0,
          "From the next step, each listed node gets `force` (3 components, N) until "
          "clear_force(slot) or another set_force on the slot. Needs `loads` in the scene's "
          "effects.")
      .def(
          "clear_force",
          [](Simulation& s, std::size_t slot) {
            s.with_backend([&](auto& b) {
              if (slot >= b.force_slot_count())
                throw ConfigError("", "slot",
                                  fmt::format("slot {} out of range (the simulation has {})", slot,
                                              b.force_slot_count()));
              b.clear_force_slot(slot);
              return 0;
            });
          },
          py::arg("slot") = 0, "Removes the slot's force from the next step.")
      .def(
          "state", [](Simulation& s) { return s.with_backend([](auto& b) { return b.state(); }); },
          "A copy of the whole dynamic state (sinew.State), for restore().")
      .def(
          "restore",
          [](Simulation& s, const simulator::State& state) {
            s.with_backend([&](auto& b) {
              b.restore(state);
              return 0;
            });
          },
          py::arg("state"),
          "Continues from a state of a simulation of the same scene and model, bit for bit. "
          "Raises sinew.ConfigError when it does not fit (node count, Δt).")
      .def(
          "explain",
          [](Simulation& s) {
            simulator::RunOptions o;
            o.scene_path = s.run_.summary.scene_file;
            return s.with_backend([&](auto&) { return simulator::explain_run(s.run_, o); });
          },
          "The plan as sinew-simulate --explain prints it.");
}

}  // namespace sinew::python
