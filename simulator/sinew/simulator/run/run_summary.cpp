#include "sinew/simulator/run/run_summary.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>

#include <nlohmann/json.hpp>

#include "sinew/common/atomic_file.hpp"
#include "sinew/common/error.hpp"

namespace sinew::simulator {

namespace {
// JSON has no NaN/Inf: a diverged energy is written as null.
nlohmann::json number(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
}
}  // namespace

std::string to_json(const RunSummary& s) {
  nlohmann::ordered_json j;
  j["status"] = s.status;
  j["message"] = s.message;
  j["scene_file"] = s.scene_file;
  j["model_file"] = s.model_file;
  j["device"] = s.device;
  j["precision"] = s.precision;
  j["threads"] = s.threads;
  j["effects"] = s.effects;
  j["duration_s"] = s.duration;
  j["time_scaling"] = s.time_scaling;
  j["mass_scaling"] = s.mass_scaling;
  j["dt_s"] = s.dt;
  j["dt_critical_s"] = s.dt_critical;
  j["dt_reason"] = s.dt_reason;
  j["steps_planned"] = s.steps_planned;
  j["steps_done"] = s.steps_done;
  j["steps_this_run"] = s.steps_this_run;
  j["restart_step"] = s.restart_step;
  j["restart_file"] = s.restart_file;
  j["simulated_time_s"] = s.simulated_time;
  j["wall_time_s"] = s.wall_time_s;
  j["time_per_step_s"] = s.time_per_step_s;
  j["setup_s"] = s.setup_s;
  auto setup = nlohmann::ordered_json::object();
  for (const auto& [name, seconds] : s.setup_stages) setup[name] = seconds;
  j["setup_stages_s"] = std::move(setup);
  j["loop_start_unix_s"] = s.loop_start_unix_s;
  j["loop_end_unix_s"] = s.loop_end_unix_s;
  // Each stage's share of the loop, as seconds and per step (time_per_step_s split by stage).
  auto stages = nlohmann::ordered_json::object();
  auto per_step = nlohmann::ordered_json::object();
  for (const auto& [name, seconds] : s.loop_stages) {
    stages[name] = seconds;
    per_step[name] = s.steps_this_run > 0 ? seconds / double(s.steps_this_run) : 0.0;
  }
  j["loop_stages_s"] = std::move(stages);
  j["time_per_step_by_stage_s"] = std::move(per_step);
  j["frame_writing_s"] = s.frame_writing_s;
  if (s.jaw_nodes > 0) {
    j["jaw"] = {{"nodes", s.jaw_nodes},
                {"max_incisal_opening_mm", 1e3 * s.jaw_max_incisal_opening}};
  }
  if (s.contact_pairs > 0) {
    j["contact"] = {{"pairs", s.contact_pairs},
                    {"effect", s.contact_on},
                    {"min_gap_mm", number(1e3 * s.contact_min_gap)},
                    {"min_gap_time_s", number(s.contact_min_gap_time)}};
  }
  j["frames"] = s.frames;
  auto energies = nlohmann::ordered_json::array();
  for (const auto& e : s.energies) {
    nlohmann::ordered_json row;
    row["step"] = e.step;
    row["time_s"] = number(e.time);
    row["kinetic_J"] = number(e.kinetic);
    row["strain_J"] = number(e.strain);
    row["elastic_J"] = number(e.elastic);
    row["hourglass_J"] = number(e.hourglass);
    row["external_work_J"] = number(e.external_work);
    energies.push_back(std::move(row));
  }
  j["energies"] = std::move(energies);
  j["warnings"] = s.warnings;
  return j.dump(2) + "\n";
}

void write_run_summary(const std::string& path, const RunSummary& summary) {
  const std::string json = to_json(summary);
  try {
    write_text_atomically(path, json);
  } catch (const IoError&) {
    // Most likely a full disk. The summary in place then says "running" (or an older frame count)
    // for a run that is ending: remove it, which also frees its space, and try once more. If that
    // fails too, no summary is better than a wrong one.
    std::remove(path.c_str());
    write_text_atomically(path, json);
  }
}

std::vector<Energies> read_energy_history(const std::string& path) {
  std::vector<Energies> out;
  std::ifstream in(path);
  if (!in) return out;
  const auto j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.contains("energies") || !j["energies"].is_array()) return out;
  const auto num = [](const nlohmann::json& row, const char* key) {
    const auto it = row.find(key);
    return it != row.end() && it->is_number() ? it->get<double>() : std::nan("");
  };
  for (const auto& row : j["energies"]) {
    if (!row.is_object() || !row.contains("step") || !row["step"].is_number_integer()) continue;
    Energies e;
    e.step = row["step"].get<std::int64_t>();
    e.time = num(row, "time_s");
    e.kinetic = num(row, "kinetic_J");
    e.strain = num(row, "strain_J");
    e.elastic = num(row, "elastic_J");
    e.hourglass = num(row, "hourglass_J");
    e.external_work = num(row, "external_work_J");
    out.push_back(e);
  }
  return out;
}

}  // namespace sinew::simulator
