#include "sinew/sweep/table.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "sinew/common/atomic_file.hpp"
#include "sinew/common/error.hpp"

namespace sinew::sweep {

namespace fs = std::filesystem;

namespace {

std::string csv_cell(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::string number_text(const std::optional<double>& v) {
  return v && std::isfinite(*v) ? fmt::format("{:.17g}", *v) : "";
}

// A parameter's YAML text as JSON: numbers, lists and maps of numbers stay numbers (flow YAML of
// numbers is JSON), anything else is a string.
nlohmann::ordered_json value_json(const std::string& text) {
  auto j = nlohmann::ordered_json::parse(text, nullptr, false);
  if (j.is_discarded() || j.is_string()) return text;
  return j;
}

}  // namespace

std::vector<Figure> table_figures(const Sweep& sweep) {
  auto out = sweep.figures;
  for (const char* key : {"steps_done", "wall_time_s"}) {
    Figure f;
    f.source = Figure::Source::summary;
    f.name = key;
    f.what = key;
    if (std::none_of(out.begin(), out.end(), [&](const Figure& g) { return g.name == key; }))
      out.push_back(f);
  }
  return out;
}

Row collect_row(const Sweep& sweep, const PlannedRun& run, const std::string& run_dir) {
  Row row;
  row.index = run.index;
  row.name = run.name;
  for (const auto& p : sweep.parameters) {
    std::string text;
    for (const auto& v : run.values)
      if (v.path == p) text = v.text;
    row.values.push_back(text);
  }
  const auto summary_path = (fs::path(run_dir) / "run_summary.json").string();
  std::ifstream in;
  if (!run_dir.empty()) in.open(summary_path);
  if (in.is_open()) {
    const auto j = nlohmann::json::parse(in, nullptr, false);
    if (j.is_discarded() || !j.is_object() || !j.contains("status") || !j["status"].is_string())
      throw FormatError(summary_path, "status", "not a run summary");
    row.status = j["status"].get<std::string>();
    if (j.contains("message") && j["message"].is_string()) row.message = j["message"];
  }
  for (const auto& f : table_figures(sweep))
    row.figures.push_back(row.status == "pending" ? std::nullopt : collect_figure(f, run_dir));
  return row;
}

std::string row_to_json(const Row& row) {
  nlohmann::json j;
  j["index"] = row.index;
  j["name"] = row.name;
  j["status"] = row.status;
  j["message"] = row.message;
  j["values"] = row.values;
  // Figures as their exact text: JSON numbers would lose NaN and infinities.
  std::vector<std::string> figures;
  for (const auto& f : row.figures) figures.push_back(f ? fmt::format("{:.17g}", *f) : "");
  j["figures"] = figures;
  return j.dump();
}

Row row_from_json(const std::string& text) {
  const auto j = nlohmann::json::parse(text, nullptr, false);
  Row row;
  try {
    if (j.is_discarded()) throw std::runtime_error("not JSON");
    row.index = j.at("index").get<std::int64_t>();
    row.name = j.at("name").get<std::string>();
    row.status = j.at("status").get<std::string>();
    row.message = j.at("message").get<std::string>();
    row.values = j.at("values").get<std::vector<std::string>>();
    for (const auto& s : j.at("figures").get<std::vector<std::string>>())
      row.figures.push_back(s.empty() ? std::nullopt
                                      : std::optional(std::strtod(s.c_str(), nullptr)));
  } catch (const std::exception& e) {
    throw FormatError("", "row", std::string("a sweep row that does not read back: ") + e.what());
  }
  return row;
}

void write_table(const Sweep& sweep, const std::vector<Row>& rows, const std::string& dir) {
  const auto figures = table_figures(sweep);
  std::string csv = "run,status,message";
  for (const auto& p : sweep.parameters) csv.append(",").append(csv_cell(p));
  for (const auto& f : figures) csv.append(",").append(csv_cell(f.name));
  csv += "\n";
  auto runs = nlohmann::ordered_json::array();
  for (const auto& r : rows) {
    csv += fmt::format("{},{},{}", r.name, r.status, csv_cell(r.message));
    nlohmann::ordered_json jr;
    jr["run"] = r.name;
    jr["status"] = r.status;
    jr["message"] = r.message;
    auto values = nlohmann::ordered_json::object();
    for (std::size_t k = 0; k < sweep.parameters.size(); ++k) {
      csv.append(",").append(csv_cell(r.values[k]));
      if (!r.values[k].empty()) values[sweep.parameters[k]] = value_json(r.values[k]);
    }
    jr["values"] = std::move(values);
    auto figs = nlohmann::ordered_json::object();
    for (std::size_t k = 0; k < figures.size(); ++k) {
      csv.append(",").append(number_text(r.figures[k]));
      // JSON has no NaN: a figure that is not a finite number is null, as a missing one.
      figs[figures[k].name] = r.figures[k] && std::isfinite(*r.figures[k])
                                  ? nlohmann::ordered_json(*r.figures[k])
                                  : nlohmann::ordered_json(nullptr);
    }
    jr["figures"] = std::move(figs);
    runs.push_back(std::move(jr));
    csv += "\n";
  }
  nlohmann::ordered_json j;
  j["format"] = "sinew-sweep-table";
  j["version"] = 1;
  j["sweep_file"] = sweep.file;
  j["title"] = sweep.title;
  j["scene"] = sweep.scene_path;
  j["parameters"] = sweep.parameters;
  auto names = nlohmann::ordered_json::array();
  for (const auto& f : figures) names.push_back(f.name);
  j["figures"] = std::move(names);
  j["runs"] = std::move(runs);
  write_text_atomically((fs::path(dir) / "sweep_table.csv").string(), csv);
  write_text_atomically((fs::path(dir) / "sweep_table.json").string(), j.dump(2) + "\n");
}

}  // namespace sinew::sweep
