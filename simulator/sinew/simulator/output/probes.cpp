#include "sinew/simulator/output/probes.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include "sinew/common/atomic_file.hpp"
#include "sinew/common/error.hpp"

namespace sinew::simulator {

std::string ProbeWriter::header(ProbeKind kind) {
  return kind == ProbeKind::reaction ? "time,step,fx,fy,fz" : "time,step,ux,uy,uz";
}

ProbeWriter::ProbeWriter(const std::string& directory, std::vector<ResolvedProbe> probes)
    : probes_(std::move(probes)) {
  try {
    for (const auto& p : probes_) {
      paths_.push_back((std::filesystem::path(directory) / file_name(p.name)).string());
      std::FILE* f = std::fopen(paths_.back().c_str(), "w");
      if (!f)
        throw IoError(paths_.back(), "", "cannot create the probe file: " + write_failure(errno));
      files_.push_back(f);
      sizes_.push_back(0);
      append(files_.size() - 1, header(p.kind) + "\n");
    }
  } catch (...) {
    // No destructor runs for a constructor that throws.
    for (auto* f : files_)
      if (f) std::fclose(f);
    throw;
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
    // In one go: a rewrite cut short by a full disk would lose the rows being kept.
    write_text_atomically(path, kept);
    std::FILE* f = std::fopen(path.c_str(), "a");
    if (!f) throw IoError(path, "", "cannot reopen the probe file: " + write_failure(errno));
    w->paths_.push_back(path);
    w->files_.push_back(f);
    w->sizes_.push_back(static_cast<std::int64_t>(kept.size()));
  }
  return w;
}

ProbeWriter::~ProbeWriter() {
  for (auto* f : files_)
    if (f) std::fclose(f);
}

void ProbeWriter::append(std::size_t i, const std::string& text) {
  std::FILE*& f = files_[i];
  if (!f) throw IoError(paths_[i], "", "the probe file was closed after a failed write");
  if (std::fputs(text.c_str(), f) >= 0 && std::fflush(f) == 0) {
    sizes_[i] += static_cast<std::int64_t>(text.size());
    return;
  }
  const int err = errno;
  // Part of the text may be on disk: cut the file back to its complete lines, so that no half row
  // is left under the probe's name (a full disk; truncating needs no space).
  std::fclose(f);
  f = nullptr;
  if (sizes_[i] == 0) {
    std::remove(paths_[i].c_str());
    throw IoError(
        paths_[i], "",
        "cannot write the probe file's header: " + write_failure(err) + "; the file was removed");
  }
  const bool cut = ::truncate(paths_[i].c_str(), static_cast<off_t>(sizes_[i])) == 0;
  throw IoError(
      paths_[i], "",
      "cannot write a probe row: " + write_failure(err) +
          (cut ? "; the file keeps the rows before it" : "; the file may end in a half row"));
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
    append(i, row);
  }
}

}  // namespace sinew::simulator
