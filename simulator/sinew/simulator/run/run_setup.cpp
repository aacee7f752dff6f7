#include "sinew/simulator/run/run_setup.hpp"
#include "sinew/simulator/run/scene_jaw.hpp"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <limits>
#include <utility>

#include <fmt/format.h>

#include "sinew/common/error.hpp"
#include "sinew/common/log.hpp"
#include "sinew/common/threads.hpp"
#include "sinew/common/yaml_reader.hpp"
#include "sinew/formats/model_file.hpp"
#include "sinew/simulator/engine/cpu_engine.hpp"
#include "sinew/simulator/engine/cuda_backend.hpp"
#include "sinew/simulator/run/run_estimate.hpp"

namespace sinew::simulator {

namespace fs = std::filesystem;

namespace {

std::string device_text(const std::string& backend, int threads) {
  return fmt::format("{} (OpenMP, {} thread{})", backend, threads, threads == 1 ? "" : "s");
}

// Whether the run goes to CUDA; a request this build or machine cannot satisfy is refused before
// any work.
bool choose_cuda(const std::string& device) {
  if (device != "cpu" && device != "auto" && device != "cuda") {
    throw ConfigError("", "--device",
                      fmt::format("unknown device '{}' (expected cpu, cuda or auto)", device));
  }
  if (device == "cuda") {
    if (!cuda_device_available()) {
#if defined(SINEW_CUDA_ENABLED)
      throw ResourceError(
          "", "--device",
          "no CUDA device is available to this process; use --device cpu (or auto)");
#else
      throw ResourceError(
          "", "--device",
          "this build of sinew has no CUDA backend (configure with "
          "-DSINEW_WITH_CUDA=ON where nvcc is available); use --device cpu (or auto)");
#endif
    }
    return true;
  }
  return device == "auto" && cuda_device_available();
}

std::unique_ptr<Backend> make_backend(bool cuda, const formats::Model& model, const Setup& setup,
                                      const RunOptions& options, const std::string& model_path) {
  const std::string& scene_path = options.scene_path;
  try {
    if (options.make_backend) return options.make_backend(model, setup);  // the caller's engine
    CudaOptions cuda_options;
    cuda_options.device = options.cuda_device;
    return cuda ? make_cuda_backend(model, setup, cuda_options) : make_cpu_backend(model, setup);
  } catch (const ConfigError& e) {
    // The engine names Setup fields; point at the scene key the user wrote instead.
    if (!e.file().empty()) throw;
    // "model" and "model.grid.voxel_size" are the model file's doing: name that file and its
    // dataset ("/grid/voxel_size"), not the scene.
    if (e.field() == "model" || e.field().rfind("model.", 0) == 0) {
      std::string dataset = e.field() == "model" ? "" : e.field().substr(5);
      std::replace(dataset.begin(), dataset.end(), '.', '/');
      auto err = ConfigError(model_path, dataset, e.problem());
      if (e.index()) err.at(*e.index());
      throw err;
    }
    static const std::pair<const char*, const char*> kKeys[] = {
        {"time_step.user_dt", "time_step.value"},
        {"time_step.safety_factor", "time_step.safety_factor"},
        {"duration", "duration"},
        {"damping_alpha", "damping"},
        {"mass_scaling", "mass_scaling"},
        {"time_scaling", "time_scaling"},
        {"hourglass.kappa", "hourglass.kappa"},
        {"gravity", "gravity"}};
    std::string key = e.field();
    for (const auto& [field, scene_key] : kKeys) {
      if (key == field) key = scene_key;
    }
    auto err = ConfigError(scene_path, key, e.problem());
    if (e.index()) err.at(*e.index());
    throw err;
  }
}

}  // namespace

std::string read_scene_text(const std::string& path) {
  return read_text_file(path, "scene file");
}

LoadedRun load_run(const RunOptions& options, const std::function<void(Setup&)>& adjust) {
  const auto start = std::chrono::steady_clock::now();
  const auto seconds_since = [](std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  };
  LoadedRun r;
  r.cuda = choose_cuda(options.device);
  const bool given = !options.scene_text.empty();
  r.scene_text = given ? options.scene_text : read_scene_text(options.scene_path);
  r.scene = parse_scene_text(
      r.scene_text, options.scene_path,
      given ? options.scene_directory : fs::path(options.scene_path).parent_path().string());
  const Scene& scene = r.scene;
  std::error_code ec;  // a name the system refuses (too long, a loop of links) is named here
  const bool model_exists = fs::exists(scene.model_path, ec);
  if (ec) {
    throw ConfigError(options.scene_path, "model",
                      fmt::format("cannot look up the model file ({} characters: '{:.60}...'): {}",
                                  scene.model.size(), scene.model, ec.message()));
  }
  if (!model_exists) {
    throw ConfigError(options.scene_path, "model",
                      fmt::format("the model file '{}' does not exist (model: {}, relative to the "
                                  "scene's folder)",
                                  scene.model_path, scene.model));
  }
  if (options.models) {
    auto file = options.models->get(scene.model_path);
    r.model_sha256 = file->sha256;
    r.model = std::shared_ptr<const formats::Model>(file, &file->model);
  } else {
    r.model = std::make_shared<const formats::Model>(formats::read_model(scene.model_path));
  }
  const formats::Model& model = *r.model;
  r.model_s = seconds_since(start);
  const auto engine_start = std::chrono::steady_clock::now();
  ResolveOptions ro;
  ro.precision = options.precision;
  ro.threads = options.threads;
  r.resolved = resolve_scene(scene, model, ro);
  if (adjust) adjust(r.resolved.setup);
  const Setup& setup = r.resolved.setup;
  if (options.make_backend) r.cuda = false;  // the caller's engine, on the host
  r.backend = make_backend(r.cuda, model, setup, options, scene.model_path);
  r.engine_s = seconds_since(engine_start);
  const Plan& plan = r.backend->plan();
  r.threads = options.threads > 0 ? options.threads : omp_get_max_threads();

  RunSummary& summary = r.summary;
  summary.scene_file = options.scene_path;
  summary.model_file = scene.model_path;
  summary.device =
      r.cuda ? "cuda (" + cuda_device_name() + ")" : device_text(r.backend->name(), r.threads);
  summary.precision = precision_name(setup.precision);
  summary.threads = r.threads;
  summary.effects = r.resolved.effects;
  summary.duration = scene.duration;
  summary.time_scaling = setup.time_scaling;
  summary.mass_scaling = setup.mass_scaling;
  summary.dt = plan.dt;
  summary.dt_critical = plan.dt_critical;
  summary.dt_reason = plan.dt_reason;
  summary.steps_planned = plan.steps;
  summary.warnings = plan.warnings;
  for (const auto& note : r.resolved.left_out) {
    log::warn("{}", note);
    summary.warnings.push_back(note);
  }
  for (const auto& p : r.resolved.probes) {
    if (p.distance > model.grid.voxel_size) {
      summary.warnings.push_back(
          fmt::format("probe '{}': the nearest node is {:.6g} m from the point (more than a voxel)",
                      p.name, p.distance));
    }
  }
  if (const auto lips = lip_contact_of(model)) {
    summary.contact_pairs = std::int64_t(lips->pairs.size());
    summary.contact_on = setup.effects.contact;
    summary.contact_min_gap = std::numeric_limits<double>::infinity();
  }
  if (setup.jaw) {
    summary.jaw_nodes = std::int64_t(setup.jaw->nodes.size());
    summary.jaw_max_incisal_opening = max_incisal_opening(setup, plan.dt, plan.steps);
  }
  r.counts = count_outputs(model, plan, r.resolved);
  return r;
}

std::string explain_run(LoadedRun& run, const RunOptions& options) {
  const std::string& output_dir = options.output_dir;
  const auto& resolved = run.resolved;
  std::string text = run.backend->plan().explain();
  if (!text.empty() && text.back() != '\n') text += '\n';
  text += fmt::format("Device: {}\n", run.summary.device);
  if (!run.cuda) text += "  " + threads::explain(run.threads, options.threads > 0) + "\n";
  text += fmt::format("Outputs: {}\n", output_dir.empty() ? "(none)" : output_dir);
  std::string fields;
  for (auto f : resolved.fields) fields += (fields.empty() ? "" : ", ") + std::string(to_string(f));
  text += fmt::format(
      "  frames every {} s of scene time ({}), fields: {}\n",
      resolved.output_interval > 0 ? fmt::format("{:.6g}", resolved.output_interval) : "-",
      resolved.output_interval > 0 ? "plus the first and last" : "first and last only", fields);
  text += describe_outputs(run.counts);
  for (const auto& p : resolved.probes)
    text += fmt::format("  probe '{}': {}\n", p.name, p.description);
  if (run.summary.jaw_nodes > 0)
    text += fmt::format("  jaw: {} nodes; incisal opening up to {:.1f} mm\n", run.summary.jaw_nodes,
                        1e3 * run.summary.jaw_max_incisal_opening);
  if (run.summary.contact_pairs > 0)
    text += fmt::format(
        "  lips: {} pairs across the cut between them, contact {} (the smallest gap over the "
        "frames goes to run_summary.json, contact.min_gap_mm)\n",
        run.summary.contact_pairs, run.summary.contact_on ? "on" : "off");
  for (const auto& w : run.summary.warnings) text += fmt::format("  warning: {}\n", w);
  const bool element_fields =
      std::any_of(resolved.fields.begin(), resolved.fields.end(), [](auto f) {
        return f == OutputField::stress || f == OutputField::jacobian ||
               f == OutputField::energy_density;
      });
  text += describe(estimate_run(*run.backend, resolved, run.counts, element_fields));
  if (options.explain_more) text += options.explain_more(*run.model, run.backend->plan());
  return text;
}

ResultsOptions results_options(const Scene& scene, const std::string& scene_path) {
  ResultsOptions ropt;
  ropt.stress = scene.output.has(OutputField::stress);
  ropt.jacobian = scene.output.has(OutputField::jacobian);
  ropt.energy_density = scene.output.has(OutputField::energy_density);
  ropt.surfaces = scene.output.has(OutputField::surfaces);
  ropt.model_file = scene.model_path;
  ropt.scene_file = scene_path;
  return ropt;
}

}  // namespace sinew::simulator
