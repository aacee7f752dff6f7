#pragma once
// Probe time series as CSV, one file per probe: <directory>/probe_<name>.csv.
//   displacement probe:  time,step,ux,uy,uz   (m, the probe's node)
//   reaction probe:      time,step,fx,fy,fz   (N, Σ of the internal nodal forces over the set: at
//                                              rest, the force the supports exert on the body)
// time is scene time (s). Every row is flushed as it is written, so an interrupted run keeps its
// rows; numbers are printed with 17 significant digits (they read back exactly). A row that cannot
// be written (a full disk) is cut off again, so a file never ends in a half row: the IoError says
// so (a header that cannot be written removes its file).
#include <array>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "sinew/simulator/engine/setup.hpp"

namespace sinew::simulator {

// What a probe records: a node's displacement, or the reaction force summed over a node set.
enum class ProbeKind { displacement, reaction };

// A probe with its node ids chosen (resolve_scene, run/scene.hpp).
struct ResolvedProbe {
  ProbeKind kind = ProbeKind::displacement;
  std::string name;
  std::vector<Index> nodes;  // displacement: one node; reaction: the set
  double distance = 0;       // displacement at a point: distance from the point to the node, m
  std::string description;   // e.g. "node 17 (nearest to [0.01, 0, 0], 0 m away)"
};

// The node of each displacement probe, in probe order: what a probe row reads of u
// (Backend::displacements(nodes)).
std::vector<Index> displacement_probe_nodes(const std::vector<ResolvedProbe>& probes);

class ProbeWriter {
 public:
  using Reaction = std::function<std::array<double, 3>(const std::vector<Index>& nodes)>;

  // Creates (truncates) one CSV per probe and writes the header rows.
  ProbeWriter(const std::string& directory, std::vector<ResolvedProbe> probes);
  // Reopens the CSVs of an interrupted run, keeping the rows whose step is ≤ last_step.
  // Throws FormatError when a file is missing or its header does not match.
  static std::unique_ptr<ProbeWriter> resume(const std::string& directory,
                                             std::vector<ResolvedProbe> probes,
                                             std::int64_t last_step);
  ~ProbeWriter();
  ProbeWriter(const ProbeWriter&) = delete;
  ProbeWriter& operator=(const ProbeWriter&) = delete;

  // One row per probe. u: N × 3 displacements (m). `reaction` is called only for reaction probes.
  void record(double time, std::int64_t step, const std::vector<double>& u,
              const Reaction& reaction);
  // The same from the probed displacements alone: 3 per entry of displacement_nodes(), in order
  // (Backend::displacements(nodes): a device copies only these).
  void record_probed(double time, std::int64_t step, const std::vector<double>& probed_u,
                     const Reaction& reaction);
  std::vector<Index> displacement_nodes() const { return displacement_probe_nodes(probes_); }

  bool empty() const { return probes_.empty(); }
  // The CSV path of probe i.
  const std::string& path(std::size_t i) const { return paths_[i]; }
  static std::string file_name(const std::string& probe_name) {
    return "probe_" + probe_name + ".csv";
  }
  static std::string header(ProbeKind kind);

 private:
  ProbeWriter() = default;
  // Writes and flushes `text` to file i, or cuts the file back to sizes_[i] and throws IoError.
  void append(std::size_t i, const std::string& text);
  std::vector<ResolvedProbe> probes_;
  std::vector<std::string> paths_;
  std::vector<std::FILE*> files_;    // null once a write failed
  std::vector<std::int64_t> sizes_;  // bytes of complete lines in each file
};

}  // namespace sinew::simulator
