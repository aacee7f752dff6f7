#include "sinew/simulator/output/probes.hpp"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include "sinew/common/error.hpp"

namespace sinew::simulator {

std::string ProbeWriter::header(ProbeKind kind) {
  return kind == ProbeKind::reaction ? "time,step,fx,fy,fz" : "time,step,ux,uy,uz";
}

ProbeWriter::ProbeWriter(const std::string& directory, std::vector<ResolvedProbe> probes)
    : probes_(std::move(probes)) {
  for (const auto& p : probes_) {
    paths_.push_back((std::filesystem::path(directory) / file_name(p.name)).string());
    std::FILE* f = std::fopen(paths_.back().c_str(), "w");
    if (!f) throw IoError(paths_.back(), "", "cannot create the probe file");
    files_.push_back(f);
    std::fprintf(f, "%s\n", header(p.kind).c_str());
    std::fflush(f);
  }
}

std::unique_ptr<ProbeWriter> ProbeWriter::resume(const std::string& directory,
                                                 std::vector<ResolvedProbe> probes,
                                                 std::int64_t last_step) {
  std::unique_ptr<ProbeWriter> w(new ProbeWriter());
  w->probes_ = std::move(probes);
  for (const auto& p : w->probes_) {
    const auto path = (std::filesystem::path(directory) / file_name(p.name)).string();
    std::ifstream in(path);
    if (!in) throw FormatError(path, "", "the probe file to resume is missing");
    std::string line, kept;
    std::getline(in, line);
    if (line != header(p.kind))
      throw FormatError(path, "header", "expected '" + header(p.kind) + "', found '" + line + "'");
    kept = line + "\n";
    while (std::getline(in, line)) {
      // A row cut short by the interruption has no newline and fewer than five fields: dropped.
      std::istringstream row(line);
      std::string time, step;
      if (!std::getline(row, time, ',') || !std::getline(row, step, ',')) break;
      if (std::count(line.begin(), line.end(), ',') != 4) break;
      char* end = nullptr;
      const long long n = std::strtoll(step.c_str(), &end, 10);
      if (end == step.c_str() || *end != '\0' || n > last_step) break;
      kept += line + "\n";
    }
    in.close();
    std::FILE* f = std::fopen(path.c_str(), "w");
    if (!f) throw IoError(path, "", "cannot rewrite the probe file");
    std::fputs(kept.c_str(), f);
    std::fflush(f);
    w->paths_.push_back(path);
    w->files_.push_back(f);
  }
  return w;
}

ProbeWriter::~ProbeWriter() {
  for (auto* f : files_) std::fclose(f);
}

std::vector<Index> displacement_probe_nodes(const std::vector<ResolvedProbe>& probes) {
  std::vector<Index> nodes;
  for (const auto& p : probes)
    if (p.kind != ProbeKind::reaction) nodes.push_back(p.nodes.front());
  return nodes;
}

void ProbeWriter::record(double time, std::int64_t step, const std::vector<double>& u,
                         const Reaction& reaction) {
  std::vector<double> probed;
  for (auto n : displacement_nodes())
    probed.insert(probed.end(), u.begin() + 3 * std::ptrdiff_t(n),
                  u.begin() + 3 * std::ptrdiff_t(n) + 3);
  record_probed(time, step, probed, reaction);
}

void ProbeWriter::record_probed(double time, std::int64_t step, const std::vector<double>& probed_u,
                                const Reaction& reaction) {
  std::size_t next = 0;  // the next displacement probe's entry in probed_u
  for (std::size_t i = 0; i < probes_.size(); ++i) {
    const auto& p = probes_[i];
    std::array<double, 3> v{};
    if (p.kind == ProbeKind::reaction) {
      v = reaction(p.nodes);
    } else {
      v = {probed_u[3 * next], probed_u[3 * next + 1], probed_u[3 * next + 2]};
      ++next;
    }
    const auto row =
        fmt::format("{:.17g},{},{:.17g},{:.17g},{:.17g}\n", time, step, v[0], v[1], v[2]);
    if (std::fputs(row.c_str(), files_[i]) < 0 || std::fflush(files_[i]) != 0) {
      throw IoError(paths_[i], "", "cannot write a probe row");
    }
  }
}

}  // namespace sinew::simulator
