#include "sinew/formats/summary.hpp"

#include <algorithm>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace sinew::formats {

ModelSummary summarize(const Model& m) {
  ModelSummary s;
  s.grid = m.grid;
  s.nodes = m.node_count();
  s.elements = m.element_count();
  const double h = m.grid.voxel_size;
  const double h3 = h * h * h;
  if (!m.node_lattice.empty()) {
    Lattice lo = m.node_lattice.front(), hi = lo;
    for (const auto& l : m.node_lattice) {
      for (std::size_t a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], l[a]);
        hi[a] = std::max(hi[a], l[a]);
      }
    }
    for (std::size_t a = 0; a < 3; ++a) {
      s.bbox_min[a] = m.grid.origin[a] + h * lo[a];
      s.bbox_max[a] = m.grid.origin[a] + h * hi[a];
    }
  }
  s.voxel_volume = static_cast<double>(s.elements) * h3;
  for (const auto& mat : m.materials) s.materials.push_back({mat.name, 0.0, 0});
  for (std::size_t i = 0; i < m.material_ids.size(); ++i) {
    auto& part = s.materials[static_cast<std::size_t>(m.material_ids[i])];
    part.volume += m.material_fractions[i] * h3;
    if (m.material_fractions[i] > 0) ++part.elements;
    s.tissue_volume += m.material_fractions[i] * h3;
  }
  for (const auto& mu : m.muscles) {
    ModelSummary::Part part{mu.name, 0.0, 0};
    for (const double f : mu.fractions) {
      part.volume += f * h3;
      if (f > 0) ++part.elements;
    }
    s.muscles.push_back(part);
  }
  s.rigid_nodes = m.rigid_nodes.size();
  s.sliding_nodes = m.sliding.size();
  s.jaw_nodes = m.jaw ? m.jaw->nodes.size() : 0;
  for (const auto& sf : m.surfaces) {
    s.surfaces.push_back({sf.name, sf.role, sf.vertices.size(), sf.triangles.size(), 0,
                          !sf.vertices.empty() && sf.embedding_element.size() == sf.vertices.size(),
                          sf.uvs.size()});
  }
  for (const auto& b : m.sliding) ++s.surfaces[static_cast<std::size_t>(b.surface)].sliding_nodes;
  for (const auto& set : m.node_sets) s.node_sets.push_back({set.name, set.ids.size()});
  for (const auto& set : m.element_sets) s.element_sets.push_back({set.name, set.ids.size()});
  s.provenance = m.provenance;
  return s;
}

namespace {
std::string point(const Point& p) {
  return fmt::format("({:.6g}, {:.6g}, {:.6g})", p[0], p[1], p[2]);
}
}  // namespace

std::string summary_text(const ModelSummary& s) {
  std::string out;
  auto line = [&out](const std::string& text) { out += text + "\n"; };
  line(fmt::format("sinew model, format version {}", kModelFormatVersion));
  line(fmt::format("grid: {} x {} x {} voxels of {:.6g} m, origin {} m", s.grid.dims[0],
                   s.grid.dims[1], s.grid.dims[2], s.grid.voxel_size, point(s.grid.origin)));
  line(fmt::format("nodes: {}, elements: {}", s.nodes, s.elements));
  line(fmt::format("bounding box: {} to {} m", point(s.bbox_min), point(s.bbox_max)));
  line(
      fmt::format("volume: tissue {:.6g} m^3, voxels {:.6g} m^3", s.tissue_volume, s.voxel_volume));
  line(fmt::format("materials ({}):", s.materials.size()));
  for (const auto& p : s.materials) {
    line(fmt::format("  {}: {:.6g} m^3 in {} elements", p.name, p.volume, p.elements));
  }
  line(fmt::format("muscles ({}):", s.muscles.size()));
  for (const auto& p : s.muscles) {
    line(fmt::format("  {}: {:.6g} m^3 in {} elements", p.name, p.volume, p.elements));
  }
  line(fmt::format("constraints: {} rigid nodes, {} sliding nodes, {} jaw nodes", s.rigid_nodes,
                   s.sliding_nodes, s.jaw_nodes));
  line(fmt::format("surfaces ({}):", s.surfaces.size()));
  for (const auto& sf : s.surfaces) {
    std::string extra;
    if (sf.role == SurfaceRole::sliding)
      extra = fmt::format(", {} sliding nodes", sf.sliding_nodes);
    if (sf.embedded) extra = ", embedded";
    if (sf.uvs > 0) extra += fmt::format(", {} texture coordinates", sf.uvs);
    line(fmt::format("  {} ({}): {} vertices, {} triangles{}", sf.name, to_string(sf.role),
                     sf.vertices, sf.triangles, extra));
  }
  auto sets = [&](const char* title, const std::vector<ModelSummary::SetInfo>& v) {
    std::string text = fmt::format("{} ({}):", title, v.size());
    for (const auto& set : v) text += fmt::format(" {} ({})", set.name, set.size);
    line(text);
  };
  sets("node sets", s.node_sets);
  sets("element sets", s.element_sets);
  const auto& p = s.provenance;
  line(fmt::format("provenance: tool '{}' version '{}', created '{}'", p.tool, p.tool_version,
                   p.created));
  for (const auto& in : p.inputs) line(fmt::format("  input {} sha256 {}", in.path, in.sha256));
  if (!p.parameters_json.empty()) {
    // One line of JSON whatever the stored formatting.
    line("  parameters " +
         nlohmann::ordered_json::parse(p.parameters_json)
             .dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace));
  }
  return out;
}

std::string summary_json(const ModelSummary& s) {
  using nlohmann::ordered_json;
  auto vec = [](const Point& p) { return ordered_json::array({p[0], p[1], p[2]}); };
  ordered_json j;
  j["format"] = kModelFormatName;
  j["format_version"] = kModelFormatVersion;
  j["grid"] = {{"origin", vec(s.grid.origin)},
               {"voxel_size", s.grid.voxel_size},
               {"dims", {s.grid.dims[0], s.grid.dims[1], s.grid.dims[2]}}};
  j["nodes"] = s.nodes;
  j["elements"] = s.elements;
  j["bounding_box"] = {{"min", vec(s.bbox_min)}, {"max", vec(s.bbox_max)}};
  j["voxel_volume"] = s.voxel_volume;
  j["tissue_volume"] = s.tissue_volume;
  auto parts = [](const std::vector<ModelSummary::Part>& v) {
    ordered_json a = ordered_json::array();
    for (const auto& p : v)
      a.push_back({{"name", p.name}, {"volume", p.volume}, {"elements", p.elements}});
    return a;
  };
  j["materials"] = parts(s.materials);
  j["muscles"] = parts(s.muscles);
  j["rigid_nodes"] = s.rigid_nodes;
  j["sliding_nodes"] = s.sliding_nodes;
  j["jaw_nodes"] = s.jaw_nodes;
  ordered_json surfaces = ordered_json::array();
  for (const auto& sf : s.surfaces) {
    surfaces.push_back({{"name", sf.name},
                        {"role", to_string(sf.role)},
                        {"vertices", sf.vertices},
                        {"triangles", sf.triangles},
                        {"sliding_nodes", sf.sliding_nodes},
                        {"embedded", sf.embedded},
                        {"uvs", sf.uvs}});
  }
  j["surfaces"] = surfaces;
  auto sets = [](const std::vector<ModelSummary::SetInfo>& v) {
    ordered_json o = ordered_json::object();
    for (const auto& set : v) o[set.name] = set.size;
    return o;
  };
  j["node_sets"] = sets(s.node_sets);
  j["element_sets"] = sets(s.element_sets);
  const auto& p = s.provenance;
  ordered_json inputs = ordered_json::array();
  for (const auto& in : p.inputs) inputs.push_back({{"path", in.path}, {"sha256", in.sha256}});
  j["provenance"] = {
      {"tool", p.tool},
      {"tool_version", p.tool_version},
      {"created", p.created},
      {"inputs", inputs},
      {"parameters",
       p.parameters_json.empty() ? ordered_json(nullptr) : ordered_json::parse(p.parameters_json)}};
  // Names are bytes from the file, not necessarily UTF-8 (the fuzz test found one): invalid bytes
  // print as U+FFFD rather than throw JSON's untyped error.
  return j.dump(2, ' ', false, ordered_json::error_handler_t::replace);
}

}  // namespace sinew::formats
