#include "sinew/fit/fit_run.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iterator>
#include <map>
#include <memory>
#include <sstream>

#include "sinew/common/atomic_file.hpp"
#include "sinew/common/error.hpp"
#include "sinew/common/log.hpp"
#include "sinew/common/yaml_reader.hpp"
#include "sinew/fit/bounded_least_squares.hpp"
#include "sinew/fit/fit_report.hpp"
#include "sinew/fit/markers.hpp"
#include "sinew/fit/response.hpp"
#include "sinew/fit/target_shapes.hpp"
#include "sinew/simulator/engine/model_cache.hpp"
#include "sinew/simulator/run/runner.hpp"
#include "sinew/simulator/run/scene.hpp"

namespace sinew::fit {
namespace fs = std::filesystem;
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// A temporary output folder removed unless committed.
class TemporaryFolder {
 public:
  explicit TemporaryFolder(fs::path path) : path_(std::move(path)) {
    std::error_code ec;
    fs::remove_all(path_, ec);
    fs::create_directories(path_);
  }
  ~TemporaryFolder() {
    if (committed_) return;
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }
  void commit(const fs::path& final_path) {
    std::error_code ec;
    if (fs::exists(final_path)) fs::remove_all(final_path, ec);
    fs::rename(path_, final_path, ec);
    if (ec)
      throw IoError(final_path.string(), "", "cannot rename the finished fit into place: " +
                                                 ec.message());
    committed_ = true;
  }

 private:
  fs::path path_;
  bool committed_ = false;
};

std::string number(double v) { return fmt::format("{:.12g}", v); }

// The muscles: mapping of curves as one line of YAML.
std::string muscles_yaml(const std::vector<std::string>& names,
                         const std::vector<std::vector<std::array<double, 2>>>& curves) {
  std::string s = "{";
  for (std::size_t k = 0; k < names.size(); ++k) {
    s += fmt::format("{}'{}': [", k ? ", " : "", names[k]);
    for (std::size_t i = 0; i < curves[k].size(); ++i)
      s += fmt::format("{}[{}, {}]", i ? ", " : "", number(curves[k][i][0]),
                       number(curves[k][i][1]));
    s += "]";
  }
  return s + "}";
}

// The jaw's degrees of freedom as the fit sees them (scene keys, docs/scene-format.md): values in
// units of `unit` (10° or 5 mm, so that a unit moves the face about as much as a muscle's full
// activation and one smoothing weight suits all), inside the scene's ranges (run/scene_jaw.hpp),
// response runs driven to `step` units: 5° of opening, 1 mm of shift (a shift of the whole
// mandible shears the voxels between its nodes and the skull's, at the ramus: 2.5 mm in the 5 ms
// of a response's ramp inverted one of the 4 mm head's).
struct JawDof {
  const char* key;
  double unit, lowest, highest;  // the key's units (degrees, mm)
  double step;                   // units
};
constexpr JawDof kJawDofs[] = {{"opening_deg", 10, 0, 40, 0.5},
                               {"protrusion_mm", 5, -1, 12, 0.2},
                               {"lateral_mm", 5, -15, 15, 0.2}};
// The jaw's response runs ramp over at least this long (response.hpp: any ramp serves): 5° in the
// 5 ms of a 200 frames/s capture's ramp inverted a voxel at the 4 mm head's ramus, 6° in 50 ms
// did not (the round trip's truth).
constexpr double kJawRamp = 0.03;  // s

// The jaw: mapping of curves (values in the keys' units) as one line of YAML.
std::string jaw_yaml(const std::vector<std::string>& keys,
                     const std::vector<std::vector<std::array<double, 2>>>& curves) {
  return muscles_yaml(keys, curves);
}

struct SceneMaker {
  YamlNode doc;
  std::string model_path;  // absolute
  std::string file;        // the base scene, for messages
  std::string probes;      // when not empty: the probes list, replaced (target nodes added)

  // The base scene with the model path absolute, the duration, the muscles' curves and (when not
  // empty) the jaw's curves, the output section and the probes replaced.
  std::string text(double duration, const std::string& muscles, const std::string& output,
                   const std::string& jaw = "") const {
    std::vector<YamlReplacement> r;
    r.push_back({"model", parse_yaml(fmt::format("'{}'", model_path), file)});
    r.push_back({"duration", parse_yaml(number(duration), file)});
    r.push_back({"muscles", parse_yaml(muscles, file)});
    if (!jaw.empty()) r.push_back({"jaw", parse_yaml(jaw, file)});
    if (!output.empty()) r.push_back({"output", parse_yaml(output, file)});
    if (!probes.empty()) r.push_back({"probes", parse_yaml(probes, file)});
    return doc.replaced(r);
  }
};

struct ForwardRun {
  std::vector<ProbePath> paths;  // one per marker
  std::int64_t steps = 0;
  double wall_s = 0;
  bool reused = false;
};

// Runs `text` in `dir` (or reuses a finished run of the same text and model there) and reads
// the markers' probe paths.
ForwardRun forward(const std::string& text, const fs::path& dir, const std::string& model_sha,
                   const std::vector<std::string>& probes, const FitOptions& o,
                   simulator::ModelCache& models, bool reuse) {
  ForwardRun r;
  const fs::path scene = dir / "scene.yaml";
  const fs::path done = dir / "fit_run_done";
  const std::string stamp = model_sha + "\n";
  bool have = false;
  if (reuse && fs::exists(done) && fs::exists(scene)) {
    try {
      have = read_text_file(scene, "scene") == text && read_text_file(done, "stamp") == stamp;
    } catch (const Error&) {
      have = false;
    }
  }
  if (!have) {
    std::error_code ec;
    fs::remove(done, ec);
    fs::create_directories(dir);
    write_text_atomically(scene.string(), text);
    simulator::RunOptions ro;
    ro.scene_path = scene.string();
    ro.output_dir = dir.string();
    ro.device = o.device;
    ro.threads = o.threads;
    ro.quiet = o.quiet;
    ro.print = [](const std::string&) {};
    ro.models = &models;
    const auto t0 = Clock::now();
    const auto result = simulator::run_scene(ro);
    if (result.summary.status != "completed")
      throw IoError(dir.string(), "", fmt::format("the run stopped ({}){}", result.summary.status,
                                                  result.summary.message.empty()
                                                      ? std::string()
                                                      : ": " + result.summary.message));
    r.wall_s = seconds_since(t0);
    r.steps = result.summary.steps_done;
    write_text_atomically(done.string(), stamp);
  } else {
    r.reused = true;
  }
  for (const auto& p : probes)
    r.paths.push_back(read_probe_path((dir / ("probe_" + p + ".csv")).string()));
  return r;
}

double median_interval(const std::vector<double>& t) {
  std::vector<double> d;
  for (std::size_t i = 1; i < t.size(); ++i) d.push_back(t[i] - t[i - 1]);
  if (d.empty()) return t.empty() ? 0 : t.front();
  std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
  return d[d.size() / 2];
}

// Markers from a run's probe paths (a folder of probe_<name>.csv): every displacement probe of
// the scene, its node's rest position plus its displacement, in the scene's length unit.
Markers markers_from_probes(const std::string& folder,
                            const std::vector<simulator::ResolvedProbe>& probes,
                            const formats::Model& model, double unit) {
  Markers m;
  m.file = folder;
  m.header_line = 1;
  std::vector<ProbePath> paths;
  std::vector<formats::Point> rest;
  for (const auto& p : probes) {
    if (p.kind != simulator::ProbeKind::displacement) continue;
    m.names.push_back(p.name);
    paths.push_back(read_probe_path((fs::path(folder) / ("probe_" + p.name + ".csv")).string()));
    rest.push_back(model.node_position(p.nodes.front()));
    if (paths.back().times != paths.front().times)
      throw FormatError((fs::path(folder) / ("probe_" + p.name + ".csv")).string(), "time",
                        "its rows' times differ from those of probe_" + m.names.front() + ".csv");
  }
  if (paths.empty())
    throw FormatError(folder, "", "the scene has no displacement probe to read as a marker");
  for (std::size_t f = 0; f < paths.front().times.size(); ++f) {
    m.times.push_back(paths.front().times[f]);
    m.lines.push_back(static_cast<int>(f) + 2);
    std::vector<std::array<double, 3>> row;
    for (std::size_t k = 0; k < paths.size(); ++k)
      row.push_back({(rest[k][0] + paths[k].u[f][0]) / unit, (rest[k][1] + paths[k].u[f][1]) / unit,
                     (rest[k][2] + paths[k].u[f][2]) / unit});
    m.positions.push_back(std::move(row));
    m.seen.push_back(std::vector<bool>(paths.size(), true));
  }
  return m;
}

void check_options(const FitOptions& o) {
  auto bad = [](const char* key, const std::string& problem) {
    return ConfigError("", key, problem);
  };
  if (!(o.max_activation > 0 && o.max_activation <= 1))
    throw bad("--max-activation", fmt::format("must lie in (0, 1], not {}", o.max_activation));
  if (!(o.knot_interval >= 0) || !std::isfinite(o.knot_interval))
    throw bad("--knot-interval", fmt::format("must be ≥ 0 s, not {}", o.knot_interval));
  if (!(o.response_ramp >= 0) || !std::isfinite(o.response_ramp))
    throw bad("--response-ramp", fmt::format("must be ≥ 0 s, not {}", o.response_ramp));
  if (!(o.step_activation > 0 && o.step_activation <= 1))
    throw bad("--step-activation", fmt::format("must lie in (0, 1], not {}", o.step_activation));
  if (!(o.smoothing > 0) || !std::isfinite(o.smoothing))
    throw bad("--smoothing", fmt::format("must be > 0, not {}", o.smoothing));
  if (!(o.effort >= 0) || !std::isfinite(o.effort))
    throw bad("--effort", fmt::format("must be ≥ 0, not {}", o.effort));
  if (o.corrections < 0 || o.corrections > 20)
    throw bad("--corrections", fmt::format("must lie in [0, 20], not {}", o.corrections));
  if (!(o.marker_unit >= 0) || !std::isfinite(o.marker_unit))
    throw bad("--marker-unit", fmt::format("must be > 0, not {}", o.marker_unit));
  if (!(o.sample_interval >= 0) || !std::isfinite(o.sample_interval))
    throw bad("--sample-interval", fmt::format("must be ≥ 0 s, not {}", o.sample_interval));
  if (o.output_dir.empty()) throw bad("--output", "no output folder given");
  if (o.markers_path.empty() && o.targets_path.empty())
    throw bad("markers", "nothing to fit: give markers (a CSV or a run's folder) or --targets");
  if (!o.markers_path.empty() && !o.targets_path.empty())
    throw bad("--targets", "give either markers (a CSV or a run's folder) or --targets, not both");
  if (o.target_markers < 0)
    throw bad("--target-markers", fmt::format("must be ≥ 0, not {}", o.target_markers));
}

// The visual surface the targets sculpt: by name, or the model's first.
const formats::Surface& target_surface(const formats::Model& model, const std::string& name,
                                       const std::string& model_path) {
  std::string list;
  for (const auto& s : model.surfaces) {
    if (s.role != formats::SurfaceRole::visual) continue;
    if (name.empty() || s.name == name) return s;
    list += (list.empty() ? "" : ", ") + s.name;
  }
  if (name.empty())
    throw ConfigError(model_path, "/surfaces",
                      "the model has no visual surface for target shapes to sculpt");
  throw ConfigError("", "--target-surface",
                    fmt::format("the model has no visual surface '{}' (it has: {})", name,
                                list.empty() ? "none" : list));
}

// The base scene's probes list with a displacement probe per target node appended.
std::string probes_with(const YamlNode& doc, const TargetMarkers& t) {
  std::string s = "[";
  for (const auto& item : doc.child("probes").items()) s += item.emit() + ", ";
  for (std::size_t p = 0; p < t.nodes.size(); ++p)
    s += fmt::format("{}{{name: {}, type: displacement, node: {}}}", p ? ", " : "", t.probes[p],
                     t.nodes[p]);
  return s + "]";
}

}  // namespace

FitResult run_fit(const FitOptions& o,
                  const std::function<void(const std::string&, const FitResult&)>& before_commit) {
  const auto start = Clock::now();
  check_options(o);
  const simulator::Scene scene = simulator::parse_scene(o.scene_path);
  const bool from_targets = !o.targets_path.empty();
  const bool from_probes = !from_targets && fs::is_directory(o.markers_path);
  const TargetManifest manifest =
      from_targets ? read_target_manifest(o.targets_path) : TargetManifest{};
  Markers markers = from_probes || from_targets ? Markers{} : read_markers(o.markers_path);
  if (!scene.has(simulator::Effect::muscles))
    throw ConfigError(o.scene_path, "effects",
                      "the base scene must list the 'muscles' effect: sinew-fit fits its "
                      "muscles' activations");
  simulator::ModelCache models;
  const auto model_file = models.get(scene.model_path);
  const formats::Model& model = model_file->model;
  const simulator::ResolvedScene resolved = simulator::resolve_scene(scene, model);

  // Every marker names a displacement probe of the scene; its node's rest position is the
  // marker's rest position.
  std::map<std::string, const simulator::ResolvedProbe*> probes;
  std::string probe_list;
  for (const auto& p : resolved.probes)
    if (p.kind == simulator::ProbeKind::displacement) {
      probes[p.name] = &p;
      probe_list += (probe_list.empty() ? "" : ", ") + p.name;
    }
  if (from_probes) markers = markers_from_probes(o.markers_path, resolved.probes, model,
                                                 scene.length_unit);
  // Target shapes: every mesh checked against the surface, then the sampled vertices' markers,
  // each read from probes on its element's nodes that the runs' scenes add.
  TargetMarkers targets;
  std::string surface_name;
  if (from_targets) {
    const auto& surface = target_surface(model, o.target_surface, scene.model_path);
    surface_name = surface.name;
    std::vector<ObjMesh> meshes;
    for (const auto& path : manifest.meshes) {
      meshes.push_back(read_obj_mesh(path));
      check_target_topology(meshes.back(), surface);
      check_target_scale(meshes.back(), surface, o.marker_unit > 0 ? o.marker_unit : 1.0);
    }
    targets = target_markers(manifest, meshes, model, surface,
                             static_cast<std::size_t>(o.target_markers));
    for (const auto& name : targets.probes)
      if (probes.count(name))
        throw ConfigError(
            o.scene_path, "probes",
            fmt::format("probe '{}' has the name of a target probe: rename it", name));
    markers = targets.markers;
  }
  std::vector<std::array<double, 3>> rest;
  if (from_targets) rest = targets.rest;
  // The probes each run records, and the markers' paths from them.
  const std::vector<std::string>& run_probes = from_targets ? targets.probes : markers.names;
  auto paths_of = [&](std::vector<ProbePath> paths) {
    return from_targets ? marker_paths(targets, paths) : paths;
  };
  for (const auto& name : from_targets ? std::vector<std::string>{} : markers.names) {
    const auto it = probes.find(name);
    if (it == probes.end())
      throw FormatError(markers.file,
                        fmt::format("line {}, column '{}.x'", markers.header_line, name),
                        fmt::format("marker '{}' names no displacement probe of the scene '{}' "
                                    "(its displacement probes: {})",
                                    name, o.scene_path,
                                    probe_list.empty() ? "none" : probe_list));
    const auto p = model.node_position(it->second->nodes.front());
    rest.push_back({p[0], p[1], p[2]});
  }

  FitResult result;
  result.output_dir = o.output_dir;
  if (o.muscles.empty()) {
    for (const auto& m : model.muscles) result.muscles.push_back(m.name);
  } else {
    for (const auto& name : o.muscles) {
      const bool known = std::any_of(model.muscles.begin(), model.muscles.end(),
                                     [&](const auto& m) { return m.name == name; });
      if (!known) {
        std::string list;
        for (const auto& m : model.muscles) list += (list.empty() ? "" : ", ") + m.name;
        throw ConfigError("", "--muscles",
                          fmt::format("unknown muscle '{}' (the model has: {})", name, list));
      }
      if (std::find(result.muscles.begin(), result.muscles.end(), name) != result.muscles.end())
        throw ConfigError("", "--muscles", fmt::format("muscle '{}' named twice", name));
      result.muscles.push_back(name);
    }
  }
  if (result.muscles.empty())
    throw ConfigError(scene.model_path, "/muscles", "the model has no muscles to fit");
  std::vector<JawDof> jaw_dofs;
  if (o.jaw == "auto") {
    if (model.jaw) jaw_dofs.assign(std::begin(kJawDofs), std::end(kJawDofs));
  } else if (o.jaw != "none") {
    std::stringstream list(o.jaw);
    std::string key;
    while (std::getline(list, key, ',')) {
      const auto* d = std::find_if(std::begin(kJawDofs), std::end(kJawDofs),
                                   [&](const JawDof& j) { return key == j.key; });
      if (d == std::end(kJawDofs))
        throw ConfigError("", "--jaw",
                          fmt::format("unknown jaw key '{}' (auto, none, or a list of "
                                      "opening_deg, protrusion_mm, lateral_mm)",
                                      key));
      if (std::any_of(jaw_dofs.begin(), jaw_dofs.end(),
                      [&](const JawDof& j) { return key == j.key; }))
        throw ConfigError("", "--jaw", fmt::format("jaw key '{}' named twice", key));
      jaw_dofs.push_back(*d);
    }
    if (!model.jaw && !jaw_dofs.empty())
      throw ConfigError(scene.model_path, "/jaw",
                        "the model has no jaw to fit (voxelize it with rig: {jaw: true}, or "
                        "--jaw none)");
  }
  for (const auto& d : jaw_dofs) result.jaw.push_back(d.key);
  // With the jaw fitted every run drives it (closed in the muscles' responses).
  const std::string jaw_closed = jaw_dofs.empty() ? "" : "{opening_deg: 0}";

  // Target meshes are in m (sinew-export writes m) unless --marker-unit says otherwise.
  const double unit = from_probes         ? scene.length_unit
                      : o.marker_unit > 0 ? o.marker_unit
                      : from_targets      ? 1.0
                                          : scene.length_unit;
  const double end_time = markers.times.back();
  if (!(end_time > 0))
    throw FormatError(markers.file, fmt::format("line {}", markers.lines.back()),
                      "the markers end at t = 0: nothing to fit");
  Knots knots;
  // J knots evenly spaced, the last at the last marker time, about the interval asked for apart;
  // the response runs' ramp (independent of the knots, so that cached runs serve any knots).
  const double frame_interval = median_interval(markers.times);
  const double ramp = o.response_ramp > 0 ? o.response_ramp : frame_interval;
  const double asked = o.knot_interval > 0 ? o.knot_interval : frame_interval;
  knots.count = std::max(1, static_cast<int>(std::lround(end_time / asked)));
  knots.interval = end_time / knots.count;
  // The runs' probes: every step unless a sample interval is given.
  const std::string work_output =
      o.sample_interval > 0
          ? fmt::format("{{interval: 0, probe_interval: {}}}", number(o.sample_interval))
          : std::string("{interval: 0}");

  // Observations, mm from rest.
  const auto rows = observations(markers);
  Eigen::VectorXd y(static_cast<Eigen::Index>(rows.size()));
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const auto& ob = rows[r];
    y[static_cast<Eigen::Index>(r)] =
        1e3 * (markers.positions[ob.frame][ob.marker][ob.component] * unit -
               rest[ob.marker][ob.component]);
  }

  // The output folder: a fresh one, or a previous fit's (replaced at the end).
  const fs::path final_dir(o.output_dir);
  if (fs::exists(final_dir) && !(fs::is_directory(final_dir) &&
                                 (fs::is_empty(final_dir) ||
                                  fs::exists(final_dir / "fit_summary.json"))))
    throw ConfigError(o.output_dir, "--output",
                      "exists and is not a sinew-fit output folder: choose another name");
  TemporaryFolder tmp(fs::path(temporary_name(fs::absolute(final_dir).lexically_normal().string())));
  const fs::path runs = tmp.path() / "runs";
  const fs::path response_root = o.cache_dir.empty() ? runs : fs::path(o.cache_dir);

  SceneMaker maker{parse_yaml(read_text_file(o.scene_path, "scene"), o.scene_path),
                   fs::absolute(scene.model_path).lexically_normal().string(),
                   o.scene_path,
                   {}};
  if (from_targets) maker.probes = probes_with(maker.doc, targets);

  // 1. Response runs.
  const auto t_response = Clock::now();
  std::vector<std::vector<ProbePath>> responses;
  for (const auto& muscle : result.muscles) {
    const std::string text =
        maker.text(end_time, muscles_yaml({muscle}, {{{0.0, 0.0}, {ramp, o.step_activation}}}),
                   work_output, jaw_closed);
    log::info("sinew-fit: response of {}", muscle);
    auto run = forward(text, response_root / ("response_" + muscle), model_file->sha256, run_probes,
                       o, models, !o.cache_dir.empty());
    result.response_runs += 1;
    result.response_runs_reused += run.reused;
    if (!run.reused) result.steps_per_run = run.steps;
    responses.push_back(paths_of(std::move(run.paths)));
  }
  std::vector<std::vector<ProbePath>> jaw_responses;
  const double jaw_ramp = std::max(ramp, kJawRamp);
  for (const auto& d : jaw_dofs) {
    const std::string text =
        maker.text(end_time, "{}", work_output,
                   jaw_yaml({d.key}, {{{0.0, 0.0}, {jaw_ramp, d.step * d.unit}}}));
    log::info("sinew-fit: response of the jaw's {}", d.key);
    auto run = forward(text, response_root / (std::string("response_jaw_") + d.key),
                       model_file->sha256, run_probes, o, models, !o.cache_dir.empty());
    result.response_runs += 1;
    result.response_runs_reused += run.reused;
    if (!run.reused) result.steps_per_run = run.steps;
    jaw_responses.push_back(paths_of(std::move(run.paths)));
  }
  result.response_s = seconds_since(t_response);

  const int M = static_cast<int>(result.muscles.size());
  const int D = static_cast<int>(jaw_dofs.size());
  const int K = M + D;  // the columns' groups: the muscles, then the jaw's keys
  const int J = knots.count;
  const auto t_solve = Clock::now();
  Eigen::MatrixXd a(static_cast<Eigen::Index>(rows.size()), static_cast<Eigen::Index>(K) * J);
  a.leftCols(static_cast<Eigen::Index>(M) * J) =
      design_matrix(responses, o.step_activation, ramp, knots, markers.times, rows);
  for (int d = 0; d < D; ++d)
    a.middleCols(static_cast<Eigen::Index>(M + d) * J, J) = design_matrix(
        {jaw_responses[static_cast<std::size_t>(d)]}, jaw_dofs[static_cast<std::size_t>(d)].step,
        jaw_ramp, knots, markers.times, rows);
  Eigen::VectorXd lower = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(K) * J);
  Eigen::VectorXd upper = Eigen::VectorXd::Constant(lower.size(), o.max_activation);
  for (int d = 0; d < D; ++d) {
    const auto& dof = jaw_dofs[static_cast<std::size_t>(d)];
    const auto at = static_cast<Eigen::Index>(M + d) * J;
    lower.segment(at, J).setConstant(dof.lowest / dof.unit);
    upper.segment(at, J).setConstant(dof.highest / dof.unit);
  }
  BoundedOptions bo;
  bo.smoothing = o.smoothing;
  bo.effort = o.effort;
  // The effort term prefers the fewest muscles; the jaw's keys are poses, not effort.
  bo.effort_weights = Eigen::VectorXd::Zero(lower.size());
  bo.effort_weights.head(static_cast<Eigen::Index>(M) * J).setOnes();
  auto solution = solve_bounded_least_squares(a, y, K, J, lower, upper, {}, bo);
  result.solve_s += seconds_since(t_solve);

  // 2. Forward runs of the fitted activations, refitting the residual with the same response.
  // The muscles' curves (activations), then the jaw's (degrees, mm).
  auto curves_of = [&](const Eigen::VectorXd& x) {
    std::vector<std::vector<std::array<double, 2>>> curves(static_cast<std::size_t>(K));
    for (int k = 0; k < K; ++k) {
      const double scale = k < M ? 1.0 : jaw_dofs[static_cast<std::size_t>(k - M)].unit;
      curves[k].push_back({0.0, 0.0});
      for (int j = 1; j <= J; ++j)
        curves[k].push_back(
            {knots.time(j),
             scale * std::clamp(x[k * J + j - 1], lower[k * J + j - 1], upper[k * J + j - 1])});
    }
    return curves;
  };
  // The scene text of curves: the muscles' mapping and (fitting the jaw) the jaw's.
  auto scene_of = [&](const std::vector<std::vector<std::array<double, 2>>>& curves,
                      const std::string& output) {
    const std::vector<std::vector<std::array<double, 2>>> muscle_curves(curves.begin(),
                                                                        curves.begin() + M);
    const std::vector<std::vector<std::array<double, 2>>> jaw_curves(curves.begin() + M,
                                                                     curves.end());
    return maker.text(end_time, muscles_yaml(result.muscles, muscle_curves), output,
                      D > 0 ? jaw_yaml(result.jaw, jaw_curves) : "");
  };
  Eigen::VectorXd best_x = solution.x;
  double best_rms = INFINITY;
  MarkerErrors best_errors;
  Eigen::VectorXd x = solution.x;
  for (int it = 0; it <= o.corrections; ++it) {
    const auto t_forward = Clock::now();
    const std::string text = scene_of(curves_of(x), work_output);
    log::info("sinew-fit: forward run {} of {}", it + 1, o.corrections + 1);
    auto run = forward(text, runs / fmt::format("forward_{}", it), model_file->sha256, run_probes,
                       o, models, false);
    run.paths = paths_of(std::move(run.paths));
    result.forward_s += seconds_since(t_forward);
    result.forward_runs += 1;
    if (result.steps_per_run == 0) result.steps_per_run = run.steps;
    const MarkerErrors errors = marker_errors(markers, rest, unit, run.paths);
    result.iteration_rms_mm.push_back(errors.rms_mm);
    log::info("sinew-fit: forward run {}: marker RMS {:.4f} mm", it + 1, errors.rms_mm);
    if (errors.rms_mm < best_rms) {
      best_rms = errors.rms_mm;
      best_x = x;
      best_errors = errors;
      result.best_iteration = it;
    }
    if (it == o.corrections) break;
    // The residual at the observations, refitted: y' = (y − u_sim) + A x.
    const auto t_refit = Clock::now();
    Eigen::VectorXd target = a * x;
    for (std::size_t r = 0; r < rows.size(); ++r) {
      const auto& ob = rows[r];
      const double sim = 1e3 * run.paths[ob.marker].at(markers.times[ob.frame])[ob.component];
      target[static_cast<Eigen::Index>(r)] += y[static_cast<Eigen::Index>(r)] - sim;
    }
    x = solve_bounded_least_squares(a, target, K, J, lower, upper, x, bo).x;
    result.solve_s += seconds_since(t_refit);
  }

  result.knot_times.push_back(0);
  for (int j = 1; j <= J; ++j) result.knot_times.push_back(knots.time(j));
  const auto curves = curves_of(best_x);
  for (int k = 0; k < K; ++k) {
    std::vector<double> v;
    for (const auto& p : curves[k]) v.push_back(p[1]);
    (k < M ? result.activations : result.jaw_values).push_back(std::move(v));
  }
  result.frame_times = markers.times;
  result.frame_rms_mm = best_errors.frame_rms_mm;
  result.frame_max_mm = best_errors.frame_max_mm;
  result.rms_mm = best_errors.rms_mm;
  result.max_mm = best_errors.max_mm;
  result.marker_names = markers.names;
  result.marker_rest = rest;
  result.marker_vertex =
      from_targets ? targets.vertices : std::vector<std::int32_t>(markers.names.size(), -1);
  result.marker_rms_mm = best_errors.marker_rms_mm;
  result.marker_max_mm = best_errors.marker_max_mm;
  result.worst_frame = best_errors.worst_frame;
  if (best_errors.worst_frame >= 0)
    result.worst_frame_residual_mm =
        best_errors.distance_mm[static_cast<std::size_t>(best_errors.worst_frame)];
  result.model_path = maker.model_path;
  result.surface = surface_name;

  // 3. Outputs: the scene that replays the fit (the base scene's own output section), the tables.
  write_text_atomically((tmp.path() / "fitted_scene.yaml").string(),
                        "# sinew-fit: " + o.scene_path + " with the activations fitted to " +
                            (from_targets ? o.targets_path : o.markers_path) + " (docs/fit.md)\n" +
                            scene_of(curves, ""));
  result.total_s = seconds_since(start);
  write_fit_tables(tmp.path().string(), result, o);
  if (before_commit) before_commit(tmp.path().string(), result);
  tmp.commit(final_dir);
  return result;
}

}  // namespace sinew::fit
