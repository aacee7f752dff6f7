// The voxelizer's summary for people and as JSON (voxelize.hpp), apart from the pipeline.
#include <cstdio>
#include <string>

#include <nlohmann/json.hpp>

#include "sinew/voxelizer/voxelize.hpp"

namespace sinew::voxelizer {

std::string format_bytes(double b) {
  char buf[64];
  if (b >= 1024.0 * 1024 * 1024) {
    std::snprintf(buf, sizeof buf, "%.2f GiB", b / (1024.0 * 1024 * 1024));
  } else {
    std::snprintf(buf, sizeof buf, "%.1f MiB", b / (1024.0 * 1024));
  }
  return buf;
}

std::string summary_json(const Summary& s) {
  nlohmann::json j;
  j["output"] = s.output;
  j["voxel_size_m"] = s.voxel_size;
  j["dims"] = s.dims;
  j["elements"] = s.elements;
  j["nodes"] = s.nodes;
  j["tissue_volume_m3"] = s.tissue_volume;
  for (const auto& v : s.material_volumes) j["material_volumes_m3"][v.name] = v.volume;
  for (const auto& v : s.muscle_volumes) j["muscle_volumes_m3"][v.name] = v.volume;
  j["rigid_nodes"] = s.rigid_nodes;
  j["sliding_nodes"] = s.sliding_nodes;
  j["cropped_voxels"] = s.cropped_voxels;
  j["cut_nodes"] = s.cut_nodes;
  j["jaw_nodes"] = s.jaw_nodes;
  j["jaw_cut_voxels"] = s.jaw_cut_voxels;
  j["lip_pairs"] = s.lip_pairs;
  for (const auto& [n, c] : s.node_sets) j["node_sets"][n] = c;
  for (const auto& m : s.meshes) {
    const auto& d = m.diagnostics;
    j["meshes"].push_back({{"role", m.role},
                           {"source", m.source},
                           {"vertices", d.vertices},
                           {"triangles", d.triangles},
                           {"duplicate_vertices_merged", d.duplicate_vertices_merged},
                           {"degenerate_triangles_removed", d.degenerate_triangles_removed},
                           {"duplicate_triangles_removed", d.duplicate_triangles_removed},
                           {"boundary_edges", d.boundary_edges},
                           {"non_manifold_edges", d.non_manifold_edges},
                           {"components", d.components},
                           {"inconsistently_oriented_edges", d.inconsistently_oriented_edges},
                           {"closed", d.closed},
                           {"area_m2", d.area},
                           {"enclosed_volume_m3", d.enclosed_volume}});
  }
  j["embedding"] = {{"vertices", s.embedded_vertices},
                    {"outside", s.embedding_outside},
                    {"max_outside_distance_m", s.embedding_max_outside_distance}};
  j["memory_estimate_bytes"] = s.memory_estimate_bytes;
  j["memory_available_bytes"] = s.memory_available_bytes;
  j["field_evaluations"] = s.field_evaluations;
  j["threads"] = s.threads;
  for (const auto& st : s.stages) {
    j["stages"].push_back({{"name", st.name},
                           {"seconds", st.seconds},
                           {"cpu_seconds", st.cpu_seconds},
                           {"peak_rss_bytes", st.peak_rss_bytes}});
  }
  j["warnings"] = s.warnings;
  return j.dump(2);
}

std::string summary_text(const Summary& s) {
  std::ostringstream o;
  char buf[256];
  auto line = [&](const char* fmt, auto... args) {
    std::snprintf(buf, sizeof buf, fmt, args...);
    o << buf << '\n';
  };
  if (!s.output.empty()) o << "model          " << s.output << '\n';
  line("grid           %d x %d x %d voxels of %.6g mm", s.dims[0], s.dims[1], s.dims[2],
       s.voxel_size * 1e3);
  line("elements       %lld", static_cast<long long>(s.elements));
  line("nodes          %lld", static_cast<long long>(s.nodes));
  line("tissue volume  %.6g mm^3", s.tissue_volume * 1e9);
  for (const auto& v : s.material_volumes) {
    line("  material %-20s %14.6g mm^3", v.name.c_str(), v.volume * 1e9);
  }
  for (const auto& v : s.muscle_volumes) {
    line("  muscle   %-20s %14.6g mm^3", v.name.c_str(), v.volume * 1e9);
  }
  line("rigid nodes    %lld", static_cast<long long>(s.rigid_nodes));
  line("sliding nodes  %lld", static_cast<long long>(s.sliding_nodes));
  if (s.cut_nodes > 0)
    line("cut nodes      %lld (on the crop's cut, held rigid)",
         static_cast<long long>(s.cut_nodes));
  if (s.jaw_nodes > 0)
    line(
        "jaw nodes      %lld (the mandible; %lld voxels cut between the lips and teeth, %lld "
        "contact pairs across the cut)",
        static_cast<long long>(s.jaw_nodes), static_cast<long long>(s.jaw_cut_voxels),
        static_cast<long long>(s.lip_pairs));
  for (const auto& [n, c] : s.node_sets)
    line("  node set %-20s %lld nodes", n.c_str(), static_cast<long long>(c));
  o << "surfaces\n";
  for (const auto& m : s.meshes) {
    const auto& d = m.diagnostics;
    line("  %-22s %lld vertices, %lld triangles, %s, %lld components", m.role.c_str(),
         static_cast<long long>(d.vertices), static_cast<long long>(d.triangles),
         d.closed ? "closed" : "open", static_cast<long long>(d.components));
    line(
        "  %-22s merged %lld vertices, removed %lld degenerate; %lld boundary, %lld non-manifold, "
        "%lld misoriented edges",
        "", static_cast<long long>(d.duplicate_vertices_merged),
        static_cast<long long>(d.degenerate_triangles_removed),
        static_cast<long long>(d.boundary_edges), static_cast<long long>(d.non_manifold_edges),
        static_cast<long long>(d.inconsistently_oriented_edges));
    line("  %-22s area %.6g mm^2, enclosed volume %.6g mm^3 (%s)", "", d.area * 1e6,
         d.enclosed_volume * 1e9, m.source.c_str());
  }
  line("embedding      %lld visual vertices, %lld outside every element",
       static_cast<long long>(s.embedded_vertices), static_cast<long long>(s.embedding_outside));
  line("memory         estimate %s, available %s", format_bytes(s.memory_estimate_bytes).c_str(),
       format_bytes(s.memory_available_bytes).c_str());
  line("stages         (%d threads, %lld field evaluations)", s.threads,
       static_cast<long long>(s.field_evaluations));
  double total = 0, cpu = 0;
  for (const auto& st : s.stages) {
    total += st.seconds;
    cpu += st.cpu_seconds;
    line("  %-12s %9.3f s  (cpu %8.3f s)   peak %s", st.name.c_str(), st.seconds, st.cpu_seconds,
         format_bytes(st.peak_rss_bytes).c_str());
  }
  line("  %-12s %9.3f s  (cpu %8.3f s)", "total", total, cpu);
  if (!s.warnings.empty()) {
    o << "warnings\n";
    for (const auto& w : s.warnings) o << "  " << w << '\n';
  }
  return o.str();
}

}  // namespace sinew::voxelizer
