#pragma once
// The voxelizer pipeline: spec -> formats::Model (paper §3, §4, §6.4; issue 3).
//
// Stages: load (meshes read, transformed to metres, cleaned, diagnosed), index (winding-number
// and distance trees; the derived inner surface when only a tissue thickness is given), checks
// (inner inside outer), estimate (memory, refused before allocating when it exceeds MemAvailable),
// fractions (fractions.hpp), model (materials, topology, muscles), fibres (fibres.hpp),
// constraints (constraints.hpp), embedding (embedding.hpp).
//
// Labels and precedence: tissue is inside the outer surface and outside the inner one; in it a
// tendon overrides a muscle, a muscle overrides a region, a region overrides the layers, and within
// each list a later entry overrides an earlier one.
//
// Deterministic: the model (provenance.created aside) does not depend on the thread count.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sinew/formats/model.hpp"
#include "sinew/voxelizer/mesh.hpp"
#include "sinew/voxelizer/spec.hpp"

namespace sinew::voxelizer {

struct VoxelizeOptions {
  int threads = 0;        // OpenMP threads; 0 = the OpenMP default
  bool progress = false;  // draw a progress bar on long stages
  // Memory the run may use (bytes); empty = MemAvailable from /proc/meminfo.
  std::optional<double> memory_limit_bytes;
  // Go past the bounds of mesh_bounds.hpp (extent against the spec's units, element count,
  // negative enclosed volume) with a warning each instead of an error (sinew-voxelize --force).
  bool force = false;
};

struct StageReport {
  std::string name;
  double seconds = 0;         // wall clock
  double cpu_seconds = 0;     // process CPU time (all threads)
  double peak_rss_bytes = 0;  // process peak resident set (VmHWM) at the end of the stage
};

struct MeshReport {
  std::string role;    // "outer", "inner", "muscles[0] frontalis", ...
  std::string source;  // path or primitive
  MeshDiagnostics diagnostics;
};

struct NamedVolume {
  std::string name;
  double volume = 0;  // m³
};

struct Summary {
  std::string output;
  double voxel_size = 0;  // m
  std::array<std::int32_t, 3> dims{0, 0, 0};
  std::int64_t elements = 0, nodes = 0;
  double tissue_volume = 0;  // m³, Σ over elements of Σ fractions · h³
  std::vector<NamedVolume> material_volumes;
  std::vector<NamedVolume> muscle_volumes;
  std::int64_t rigid_nodes = 0, sliding_nodes = 0;
  std::int64_t cropped_voxels = 0;  // tissue voxels outside the crop region, dropped
  std::int64_t cut_nodes = 0;       // nodes on the crop's cut, held rigid
  std::int64_t jaw_nodes = 0;       // the mandible's nodes (rig.jaw), apart from the rigid ones
  std::int64_t jaw_cut_voxels = 0;  // voxels removed between the lips and along the teeth
  std::int64_t lip_pairs = 0;       // contact pairs across that cut (formats::Jaw::lip_pairs)
  std::vector<std::pair<std::string, std::int64_t>> node_sets;
  std::vector<MeshReport> meshes;
  std::int64_t embedded_vertices = 0, embedding_outside = 0;
  double embedding_max_outside_distance = 0;  // m
  double memory_estimate_bytes = 0, memory_available_bytes = 0;
  std::int64_t field_evaluations = 0;
  int threads = 1;
  std::vector<StageReport> stages;
  std::vector<std::string> warnings;
};

struct VoxelizeResult {
  formats::Model model;
  Summary summary;
};

// Runs the pipeline. Throws ConfigError, IoError, FormatError, GeometryError (bad meshes: empty,
// NaN, inner not inside outer, a muscle outside the tissue, no tissue at all), ResourceError
// (memory estimate above the limit; the message gives the estimate). Writes no file.
VoxelizeResult voxelize(const Spec& spec, const VoxelizeOptions& options = {});

// "1.50 GiB" or "12.3 MiB": how the summary and the memory error print a size in bytes.
std::string format_bytes(double bytes);

// The summary for people (several lines) and as one JSON document (summary_output.cpp).
std::string summary_text(const Summary& s);
std::string summary_json(const Summary& s);

// MemAvailable from /proc/meminfo (bytes); 0 when unknown.
double available_memory_bytes();
// VmHWM of this process (bytes); 0 when unknown.
double peak_rss_bytes();

}  // namespace sinew::voxelizer
