#include "sinew/live/session.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <unordered_map>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "sinew/common/atomic_file.hpp"
#include "sinew/common/error.hpp"
#include "sinew/common/log.hpp"
#include "sinew/simulator/output/results_writer.hpp"

namespace sinew::live {

using nlohmann::json;
using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;

namespace {

// A new folder for a recording: `base` when it does not exist yet, else base-2, base-3, … . Each
// try is one mkdir, which fails on a folder that exists, so two recordings (one session recording
// twice into its --record folder, two started in the same second under the default name, two
// processes in one working directory) never share a folder, and none replaces another's files.
std::string claim_recording_folder(const std::string& base) {
  fs::path path = fs::path(base).lexically_normal();
  if (!path.has_filename()) path = path.parent_path();  // "rec/" as "rec"
  std::error_code ec;
  if (path.has_parent_path()) {
    fs::create_directories(path.parent_path(), ec);
    if (ec) throw IoError(base, "", "cannot create the recording folder: " + ec.message());
  }
  constexpr int kTries = 1000;
  for (int k = 1; k <= kTries; ++k) {
    const fs::path p = k == 1 ? path : fs::path(fmt::format("{}-{}", path.string(), k));
    if (fs::create_directory(p, ec)) return p.string();
    if (ec && ec != std::errc::file_exists)
      throw IoError(p.string(), "", "cannot create the recording folder: " + ec.message());
  }
  throw IoError(base, "",
                fmt::format("cannot create the recording folder: it and {} numbered ones "
                            "beside it exist already",
                            kTries - 1));
}

SurfaceView make_surface_view(const formats::Model& model, const std::string& name) {
  const formats::Surface* chosen = nullptr;
  for (const auto& s : model.surfaces) {
    if (s.role != formats::SurfaceRole::visual) continue;
    if (name.empty() ? chosen == nullptr : s.name == name) chosen = &s;
  }
  if (!chosen) {
    throw ConfigError("", "--surface",
                      name.empty() ? std::string("the model has no visual surface to show")
                                   : fmt::format("the model has no visual surface '{}'", name));
  }
  SurfaceView v;
  v.name = chosen->name;
  std::unordered_map<formats::Index, std::uint32_t> slot;
  for (std::size_t i = 0; i < chosen->vertices.size(); ++i) {
    for (int k = 0; k < 3; ++k) v.rest.push_back(float(chosen->vertices[i][std::size_t(k)]));
    const auto e = chosen->embedding_element[i];
    const auto& q = chosen->embedding_local[i];
    std::array<std::pair<std::uint32_t, double>, 8> w{};
    for (std::size_t a = 0; a < 8; ++a) {
      const auto& c = formats::kHexCorner[a];
      // The trilinear shape function of corner a at (ξ, η, ζ), as surface_positions uses.
      const double na = (1 + (2 * c[0] - 1) * q[0]) * (1 + (2 * c[1] - 1) * q[1]) *
                        (1 + (2 * c[2] - 1) * q[2]) / 8;
      const auto node = model.element_nodes[std::size_t(e)][a];
      auto [it, added] = slot.emplace(node, std::uint32_t(v.nodes.size()));
      if (added) v.nodes.push_back(node);
      w[a] = {it->second, na};
    }
    v.weights.push_back(w);
    v.element.push_back(e);
  }
  for (const auto& t : chosen->triangles)
    for (auto id : t) v.triangles.push_back(std::uint32_t(id));
  return v;
}

// Where a results file stores an element field per frame (docs/results-format.md), and the scene's
// output.fields entry that writes it.
const char* results_dataset(Field f) {
  return f == Field::von_mises ? "/frames/von_mises" : "/frames/J";
}
const char* output_field(Field f) {
  return f == Field::von_mises ? "stress" : "J";
}

double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

}  // namespace

void make_live_setup(simulator::Setup& setup) {
  setup.activation_overrides = setup.effects.muscles;
  setup.force_slots = setup.effects.loads ? 1 : 0;
}

void make_playback_setup(simulator::Setup& setup) {
  setup.force_slots = setup.effects.loads ? 1 : 0;
}

Session::Session(simulator::LoadedRun run, SessionOptions options)
    : run_(std::move(run)), options_(std::move(options)) {
  surface_ = make_surface_view(*run_.model, options_.surface);
  for (const auto& m : run_.model->muscles) muscle_names_.push_back(m.name);
  mesh_ = std::make_shared<const std::string>(encode_mesh(surface_.rest, surface_.triangles));
  initial_ = run_.backend->state();
  step_ = run_.backend->step_index();
  paused_ = options_.start_paused;
  if (!options_.play.empty()) {
    playback_ = std::make_unique<RecordedRun>(options_.play);
    if (playback_->nodes() != run_.model->node_count())
      throw FormatError(options_.play, "/frames/displacement",
                        fmt::format("{} nodes, but the scene's model has {}", playback_->nodes(),
                                    run_.model->node_count()));
    json fields = json::array({field_name(Field::displacement)});
    for (const auto f : {Field::von_mises, Field::jacobian}) {
      const auto width = playback_->element_field_width(results_dataset(f));
      if (width == 0) continue;
      if (width != run_.model->element_count())
        throw FormatError(options_.play, results_dataset(f),
                          fmt::format("{} elements, but the scene's model has {}", width,
                                      run_.model->element_count()));
      fields.push_back(field_name(f));
      playback_fields_[std::size_t(f)] = true;
    }
    playback_hello_ = json({{"file", playback_->path()},
                            {"times", playback_->times()},
                            {"steps", playback_->steps()},
                            {"fields", fields}})
                          .dump();
    playing_ = true;
    paused_ = true;
  }
  if (!options_.record_dir.empty()) start_recording(options_.record_dir);
}

Session::~Session() {
  stop();
}

void Session::set_sink(Sink sink) {
  std::lock_guard lock(mutex_);
  sink_ = std::move(sink);
}

void Session::start() {
  if (thread_.joinable()) return;
  stop_ = false;
  thread_ = std::thread([this] { loop(); });
}

void Session::stop() {
  stop_ = true;
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void Session::submit(const Command& c) {
  if (c.kind == Command::Kind::activation) {
    if (!run_.resolved.setup.effects.muscles)
      throw ProtocolError("the scene does not simulate muscles (effect 'muscles')");
    if (std::find(muscle_names_.begin(), muscle_names_.end(), c.muscle) == muscle_names_.end())
      throw ProtocolError(fmt::format("unknown muscle '{}'", c.muscle.substr(0, 64)));
  }
  const bool playback_command =
      c.kind == Command::Kind::seek || c.kind == Command::Kind::resume_from;
  if (playing_ && !playback_command && c.kind != Command::Kind::field)
    throw ProtocolError("playing back a results file: continue from a frame first");
  if (!playing_ && playback_command)
    throw ProtocolError("not playing back a results file (sinew-live --play RESULTS.h5)");
  // playback_fields_, fixed at construction: playback_ itself goes when the engine continues.
  if (playing_ && c.kind == Command::Kind::field && !playback_fields_[std::size_t(c.field)])
    throw ProtocolError(
        fmt::format("the results file has no {} ({}: the scene's output.fields '{}' writes it)",
                    field_name(c.field), results_dataset(c.field), output_field(c.field)));
  if (c.kind == Command::Kind::drag && !drag_refusal().empty()) throw ProtocolError(drag_refusal());
  std::lock_guard lock(mutex_);
  if (queue_.size() >= 4096) throw ProtocolError("too many queued commands: dropped");
  queue_.push_back(c);
  ++submitted_;
  wake_.notify_all();
}

bool Session::wait_idle(double timeout_seconds) {
  std::unique_lock lock(mutex_);
  const std::uint64_t target = submitted_;
  return idle_.wait_for(lock, std::chrono::duration<double>(timeout_seconds),
                        [&] { return applied_ >= target; });
}

std::string Session::drag_refusal() const {
  // The slot exists when the plan asked for one (make_live_setup: effect 'loads') and the backend
  // has force slots: whichever backend that is, the drag goes through Backend::set_force_slot.
  if (run_.backend->force_slot_count() > 0) return "";
  return run_.resolved.setup.effects.loads
             ? "drag forces are not available on this backend (use --device cpu)"
             : "dragging needs the scene's effect 'loads'";
}

std::string Session::last_error() const {
  std::lock_guard lock(mutex_);
  return error_;
}

std::shared_ptr<const std::string> Session::latest_frame() const {
  std::lock_guard lock(mutex_);
  return latest_frame_;
}

std::shared_ptr<const std::string> Session::latest_status() const {
  std::lock_guard lock(mutex_);
  return latest_status_;
}

std::string Session::hello_json() const {
  const auto& setup = run_.resolved.setup;
  json muscles = json::array();
  for (std::size_t m = 0; m < muscle_names_.size(); ++m)
    muscles.push_back({{"name", muscle_names_[m]}, {"index", m}});
  json j = {{"type", "hello"},
            {"protocol", kProtocolVersion},
            {"scene", run_.summary.scene_file},
            {"title", run_.scene.title},
            {"device", run_.summary.device},
            {"precision", run_.summary.precision},
            {"effects", run_.resolved.effects},
            {"dt", run_.backend->dt()},
            {"time_scaling", setup.time_scaling},
            {"duration", run_.scene.duration},
            {"voxel_size", run_.model->grid.voxel_size},
            {"surface", surface_.name},
            {"vertices", surface_.rest.size() / 3},
            {"triangles", surface_.triangles.size() / 3},
            {"frame_bytes", kFrameHeaderBytes + 16 * (surface_.rest.size() / 3)},
            {"frame_rate", options_.frame_rate},
            {"up", options_.up},
            {"muscles", setup.effects.muscles ? muscles : json::array()},
            {"drag", drag_refusal().empty()},
            {"drag_refusal", drag_refusal().empty() ? json(nullptr) : json(drag_refusal())},
            {"drag_radius", options_.drag_radius_default > 0 ? options_.drag_radius_default
                                                             : 3 * run_.model->grid.voxel_size},
            {"warnings", run_.summary.warnings}};
  if (playing_) j["playback"] = json::parse(playback_hello_);
  return j.dump(-1, ' ', false, json::error_handler_t::replace);
}

std::vector<formats::Index> Session::nodes_near(const std::array<double, 3>& point, double radius) {
  // Current positions: rest + u(n); the picked point is on the deformed skin.
  const auto u = run_.backend->displacements();
  const auto& model = *run_.model;
  std::vector<formats::Index> out;
  const double r2 = radius * radius;
  for (std::size_t i = 0; i < model.node_count(); ++i) {
    const auto rest = model.node_position(formats::Index(i));
    double d2 = 0;
    for (std::size_t k = 0; k < 3; ++k) {
      const double d = rest[k] + u[3 * i + k] - point[k];
      d2 += d * d;
    }
    if (d2 <= r2) out.push_back(formats::Index(i));
  }
  return out;
}

void Session::apply(const Command& c) {
  auto& backend = *run_.backend;
  const std::int64_t n = backend.step_index();
  switch (c.kind) {
    case Command::Kind::activation: {
      const auto m = std::size_t(std::find(muscle_names_.begin(), muscle_names_.end(), c.muscle) -
                                 muscle_names_.begin());
      backend.set_activation_override(m, c.value);
      log_.activations.push_back({n, m, backend.activation_override(m)});
      log_.events.emplace_back(
          n, c.value
                 ? fmt::format("activation {} = {:.17g}", c.muscle, *backend.activation_override(m))
                 : fmt::format("activation {} back to its curve", c.muscle));
      break;
    }
    case Command::Kind::pause:
      paused_ = true;
      pending_steps_ = 0;
      log_.events.emplace_back(n, "pause");
      break;
    case Command::Kind::resume:
      paused_ = false;
      log_.events.emplace_back(n, "resume");
      break;
    case Command::Kind::step:
      pending_steps_ = std::min(pending_steps_ + c.count, kMaxStepCount);
      break;
    case Command::Kind::reset: {
      finish_recording();
      backend.restore(initial_);
      for (std::size_t m = 0; m < muscle_names_.size(); ++m)
        if (run_.resolved.setup.effects.muscles) backend.set_activation_override(m, std::nullopt);
      for (std::size_t k = 0; k < backend.force_slot_count(); ++k) backend.clear_force_slot(k);
      log_.clear();
      dragging_ = false;
      pending_steps_ = 0;
      at_end_ = false;
      std::lock_guard lock(mutex_);
      error_.clear();
      break;
    }
    case Command::Kind::drag: {
      // While a drag is held its nodes stay those picked first; only the force follows the mouse
      // (so the search, which copies every node's displacement off a GPU, runs once per press).
      const auto nodes = dragging_ ? log_.drags.back().nodes : nodes_near(c.point, c.radius);
      if (nodes.empty())
        throw ProtocolError(fmt::format("no node within {:.4g} m of the picked point", c.radius));
      // Per node total · (1 / n): exactly how prepare_model spreads the reproducing scene's force.
      const double k = 1.0 / double(nodes.size());
      const std::array<double, 3> per_node{c.force[0] * k, c.force[1] * k, c.force[2] * k};
      if (dragging_) {
        if (log_.drags.back().total == c.force) break;
        if (log_.drags.back().start == n) {
          log_.drags.back().total = c.force;  // not stepped yet: replace
        } else {
          log_.drags.back().end = n;
          log_.drags.push_back({n, -1, nodes, c.force});
        }
      } else {
        log_.drags.push_back({n, -1, nodes, c.force});
        log_.events.emplace_back(n, fmt::format("drag on {} nodes", nodes.size()));
      }
      backend.set_force_slot(0, nodes, per_node);
      dragging_ = true;
      break;
    }
    case Command::Kind::release:
      if (dragging_) {
        if (log_.drags.back().start == n)
          log_.drags.pop_back();  // never stepped
        else
          log_.drags.back().end = n;
        backend.clear_force_slot(0);
        dragging_ = false;
        log_.events.emplace_back(n, "release");
      }
      break;
    case Command::Kind::record:
      if (c.on && !writer_) {
        start_recording(!options_.record_dir.empty()
                            ? options_.record_dir
                            : fmt::format("sinew-live-recording-{}",
                                          std::chrono::duration_cast<std::chrono::seconds>(
                                              std::chrono::system_clock::now().time_since_epoch())
                                              .count()));
      } else if (!c.on) {
        finish_recording();
      }
      break;
    case Command::Kind::field:
      field_ = c.field;
      if (playing_) seek(shown_frame_);  // the shown frame in the new colours
      break;
    case Command::Kind::seek:
      seek(std::size_t(c.count));
      break;
    case Command::Kind::resume_from: {
      // Replay the scene from step 0 to the shown frame (exact: playback.hpp), then go on live.
      const std::int64_t target = playback_->steps()[shown_frame_];
      backend.restore(initial_);
      pending_steps_ = target;
      paused_ = true;
      playing_ = false;
      playback_.reset();
      log_.clear();
      log_.events.emplace_back(0, fmt::format("continue from step {} (replayed)", target));
      break;
    }
  }
  if (c.id) last_id_ = c.id;
  changed_ = true;
}

void Session::start_recording(const std::string& base) {
  const std::string dir = claim_recording_folder(base);
  const auto& r = run_.resolved;
  writer_ = std::make_unique<simulator::ResultsWriter>(
      dir, *run_.model, simulator::results_options(run_.scene, run_.summary.scene_file));
  record_dir_ = dir;
  schedule_.emplace(r.output_interval, r.setup.time_scaling, run_.backend->dt(),
                    std::numeric_limits<std::int64_t>::max(), false);
  next_record_ = run_.backend->step_index();
  last_recorded_ = -1;
  log::info("recording to {}", dir);
}

void Session::record_frame_if_due() {
  if (!writer_) return;
  auto& backend = *run_.backend;
  const std::int64_t n = backend.step_index();
  if (n != next_record_ || n == last_recorded_) return;
  const auto ropt = simulator::results_options(run_.scene, run_.summary.scene_file);
  const bool fields = ropt.stress || ropt.jacobian || ropt.energy_density;
  writer_->append_frame(backend.time() / run_.resolved.setup.time_scaling, n,
                        backend.displacements(),
                        fields ? backend.element_fields() : simulator::ElementFields{});
  last_recorded_ = n;
  next_record_ = schedule_->next_after(n);
}

void Session::finish_recording() {
  if (!writer_) return;
  auto& backend = *run_.backend;
  const std::int64_t n = backend.step_index();
  next_record_ = n;
  record_frame_if_due();  // the last frame, as a batch run ends with one
  const double dt = backend.dt(), s = run_.resolved.setup.time_scaling;
  const fs::path dir(record_dir_);
  write_text_atomically((dir / "steering_log.json").string(), steering_log_json(log_, dt, s, n));
  write_text_atomically((dir / "scene.yaml").string(),
                        reproduce_scene(run_.scene, run_.scene_text, run_.resolved.setup.activation,
                                        muscle_names_, dt, s, n, log_));
  auto summary = run_.summary;
  summary.status = "completed";
  summary.steps_done = n;
  summary.simulated_time = backend.time() / s;
  summary.frames = writer_->frame_count();
  simulator::write_run_summary((dir / "run_summary.json").string(), summary);
  log::info("recorded {} frames to {} (reproduce: sinew-simulate {} -o OUT)",
            writer_->frame_count(), record_dir_, (dir / "scene.yaml").string());
  writer_.reset();
}

void Session::publish_frame() {
  if (playing_) return;  // playback shows the file's frames (seek), not the engine's
  auto& backend = *run_.backend;
  std::vector<double> values;
  if (field_ != Field::displacement) {
    auto fields = backend.element_fields();
    values = std::move(field_ == Field::von_mises ? fields.von_mises : fields.jacobian);
  }
  publish_surface(backend.displacements(surface_.nodes), values, backend.step_index(),
                  backend.time() / run_.resolved.setup.time_scaling);
}

void Session::seek(std::size_t frame) {
  const auto u = playback_->displacement(frame);
  std::vector<double> sub;
  sub.reserve(3 * surface_.nodes.size());
  for (auto n : surface_.nodes)
    for (std::size_t k = 0; k < 3; ++k) sub.push_back(u[3 * std::size_t(n) + k]);
  shown_frame_ = frame;
  // submit() lets only the file's fields through; the file's own values, as the live view's.
  const auto values = field_ == Field::displacement
                          ? std::vector<double>{}
                          : playback_->element_field(results_dataset(field_), frame);
  publish_surface(sub, values, playback_->steps()[frame], playback_->times()[frame]);
}

void Session::publish_surface(const std::vector<double>& sub,
                              const std::vector<double>& element_values, std::int64_t step,
                              double time) {
  const std::size_t nv = surface_.weights.size();
  std::vector<float> disp(nv * 3), values(nv);
  for (std::size_t v = 0; v < nv; ++v) {
    double d[3] = {0, 0, 0};
    for (const auto& [slot, w] : surface_.weights[v])
      for (std::size_t k = 0; k < 3; ++k) d[k] += w * sub[3 * slot + k];
    for (std::size_t k = 0; k < 3; ++k) disp[3 * v + k] = float(d[k]);
    // An element field: the value of the vertex's embedding element (one-point quadrature makes
    // it constant per element; no smoothing, so the colours show the elements' own values).
    values[v] = field_ == Field::displacement
                    ? float(std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]))
                    : float(element_values[std::size_t(surface_.element[v])]);
  }
  publish(
      std::make_shared<const std::string>(encode_frame(step, time, field_, last_id_, disp, values)),
      true, latest_frame_);
}

void Session::publish(std::shared_ptr<const std::string> msg, bool binary,
                      std::shared_ptr<const std::string>& latest) {
  Sink sink;
  {
    std::lock_guard lock(mutex_);
    latest = msg;
    sink = sink_;
  }
  if (sink) sink(std::move(msg), binary);
}

void Session::publish_status() {
  auto& backend = *run_.backend;
  json overrides = json::object();
  if (run_.resolved.setup.effects.muscles)
    for (std::size_t m = 0; m < muscle_names_.size(); ++m) {
      const auto a = backend.activation_override(m);
      overrides[muscle_names_[m]] = a ? json(*a) : json(nullptr);
    }
  std::string error;
  {
    std::lock_guard lock(mutex_);
    error = error_;
  }
  json j = {
      {"type", "status"},
      {"step", backend.step_index()},
      {"time", backend.time() / run_.resolved.setup.time_scaling},
      {"paused", paused_.load()},
      {"at_end", at_end_},
      {"steps_per_second", steps_per_second_},
      {"sim_seconds_per_wall_second", sim_per_wall_},
      {"recording", writer_ ? json(record_dir_) : json(nullptr)},
      {"dragging", dragging_},
      {"field", field_name(field_)},
      {"overrides", overrides},
      {"last_id", last_id_},
      {"error", error.empty() ? json(nullptr) : json(error)},
      {"playback", playing_ ? json({{"frame", shown_frame_}, {"frames", playback_->frame_count()}})
                            : json(nullptr)}};
  auto msg =
      std::make_shared<const std::string>(j.dump(-1, ' ', false, json::error_handler_t::replace));
  publish(std::move(msg), false, latest_status_);
}

void Session::stop_with_error(const std::string& message) {
  paused_ = true;
  pending_steps_ = 0;
  // The step it stopped at is published before the message: a reader that sees the error (the
  // page's status, last_error()) then reads that step, not the one before the failed chunk, which
  // step_ still held until the loop updated it after the catch (issue 34, item 9: a test reading
  // step_index() right after last_error() failed once in ten loaded runs).
  step_ = run_.backend->step_index();
  {
    std::lock_guard lock(mutex_);
    error_ = message;
  }
  log::warn("live: {}", message);
  changed_ = true;
}

void Session::loop() {
  auto& backend = *run_.backend;
  const double frame_period = 1.0 / std::max(1.0, options_.frame_rate);
  auto last_frame = Clock::now() - std::chrono::seconds(1), last_status = last_frame;
  auto rate_start = Clock::now();
  // Pacing (max_speed): simulated time since pace_step may run at most max_speed × the wall time
  // since pace_wall; restarted whenever the engine was not running.
  auto pace_wall = Clock::now();
  std::int64_t pace_step = backend.step_index();
  std::int64_t rate_steps = 0, last_frame_step = -1;
  chunk_ = 1;
  try {
    if (playing_)
      seek(0);
    else
      publish_frame();
  } catch (const std::exception& e) {
    stop_with_error(e.what());
  }
  publish_status();
  while (!stop_) {
    std::vector<Command> commands;
    std::uint64_t taken = 0;
    {
      std::lock_guard lock(mutex_);
      commands.swap(queue_);
      taken = submitted_;
    }
    for (const auto& c : commands) {
      try {
        apply(c);
      } catch (const std::exception& e) {
        std::lock_guard lock(mutex_);
        if (sink_) sink_(std::make_shared<const std::string>(error_message(e.what(), c.id)), false);
      }
    }
    step_ = backend.step_index();  // reset and continue move it too
    {
      std::lock_guard lock(mutex_);
      applied_ = taken;
    }
    idle_.notify_all();
    try {
      record_frame_if_due();
    } catch (const Error& e) {
      log::error("recording stopped: {}", e.what());
      writer_.reset();
    }
    const std::int64_t n = backend.step_index();
    if (options_.pause_at_end && !at_end_ && n >= run_.backend->plan().steps && n > 0 && !paused_ &&
        pending_steps_ == 0) {
      // The scene's duration is reached: pause once; resume runs on past it.
      at_end_ = true;
      paused_ = true;
      changed_ = true;
    }
    const bool run = !paused_ || pending_steps_ > 0;
    if (!run || pending_steps_ > 0) {
      pace_wall = Clock::now();
      pace_step = backend.step_index();
    }
    // Simulated time ahead of max_speed × wall time since pace_wall, in wall seconds (≤ 0: behind).
    const auto ahead = [&] {
      return double(backend.step_index() - pace_step) * backend.dt() /
                 run_.resolved.setup.time_scaling / options_.max_speed -
             seconds_since(pace_wall);
    };
    // Paced: no step while ahead (the wait below is at most a frame period, so a chunk's lead is
    // waited off over as many turns as it takes).
    const bool step_now = run && !(options_.max_speed > 0 && pending_steps_ == 0 && ahead() > 0);
    if (step_now) {
      std::int64_t k = chunk_;
      if (pending_steps_ > 0) k = std::min(k, pending_steps_);
      if (writer_ && next_record_ > n) k = std::min(k, next_record_ - n);
      // The pause at the scene's end falls on its last step, where the batch run ends.
      const std::int64_t end = run_.backend->plan().steps;
      if (options_.pause_at_end && !at_end_ && n < end) k = std::min(k, end - n);
      const auto t0 = Clock::now();
      try {
        backend.step(k);
      } catch (const InstabilityError& e) {
        stop_with_error(e.what());
      } catch (const std::exception& e) {
        // Any other failure (a device error, memory) stops the engine as an instability does,
        // instead of ending the process with the engine thread: the page shows the message, and
        // a recording is finished at stop.
        stop_with_error(fmt::format("the engine failed: {}", e.what()));
      }
      const auto elapsed = Clock::now() - t0;
      const double wall = std::chrono::duration<double>(elapsed).count();
      const std::int64_t done = backend.step_index() - n;
      steps_run_ += done;
      stepping_ns_ += std::chrono::duration_cast<std::chrono::nanoseconds>(elapsed).count();
      pending_steps_ = std::max<std::int64_t>(0, pending_steps_ - done);
      if (pending_steps_ == 0 && paused_) changed_ = true;  // show where stepping stopped
      step_ = backend.step_index();
      rate_steps += done;
      // Chunks of about chunk_seconds: commands wait at most that long for the step loop.
      if (wall < 0.5 * options_.chunk_seconds)
        chunk_ = std::min(chunk_ * 2, std::max<std::int64_t>(1, backend.preferred_step_count()));
      else if (wall > 2 * options_.chunk_seconds)
        chunk_ = std::max<std::int64_t>(1, chunk_ / 2);
    }
    if (seconds_since(rate_start) > 0.5) {
      const double elapsed = seconds_since(rate_start);
      steps_per_second_ = double(rate_steps) / elapsed;
      sim_per_wall_ = steps_per_second_ * backend.dt() / run_.resolved.setup.time_scaling;
      rate_start = Clock::now();
      rate_steps = 0;
    }
    const bool frame_due = seconds_since(last_frame) >= frame_period;
    if (changed_ || (frame_due && backend.step_index() != last_frame_step)) {
      try {
        publish_frame();
      } catch (const std::exception& e) {
        stop_with_error(fmt::format("cannot take a frame: {}", e.what()));
      }
      last_frame = Clock::now();
      last_frame_step = backend.step_index();
    }
    if (changed_ || seconds_since(last_status) >= 0.25) {
      publish_status();
      last_status = Clock::now();
    }
    changed_ = false;
    if (run && options_.max_speed > 0) {
      const double lead = ahead();
      if (lead > 0) {
        std::unique_lock lock(mutex_);
        wake_.wait_for(lock, std::chrono::duration<double>(std::min(lead, frame_period)),
                       [&] { return !queue_.empty() || stop_.load(); });
      }
    }
    if (!run) {
      std::unique_lock lock(mutex_);
      wake_.wait_for(lock, std::chrono::duration<double>(frame_period),
                     [&] { return !queue_.empty() || stop_.load(); });
    }
  }
  try {
    finish_recording();
  } catch (const Error& e) {
    log::error("{}", e.what());
  }
}

}  // namespace sinew::live
