#include "sinew/voxelizer/landmarks.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>

#include "sinew/common/error.hpp"
#include "sinew/common/names.hpp"
#include "sinew/common/yaml_reader.hpp"

namespace sinew::voxelizer {
namespace {

struct Entry {
  const char* name;
  const char* where;
};

// Left and right are the subject's. The order is the files' order.
const std::vector<Entry>& entries() {
  static const std::vector<Entry> e{
      {"hairline", "midline, where the forehead's skin meets the scalp (trichion)"},
      {"glabella", "midline, the skin between the brows, at the brows' height"},
      {"brow_centre_left", "middle of the left eyebrow"},
      {"brow_centre_right", "middle of the right eyebrow"},
      {"eye_inner_left", "inner corner of the left eye (endocanthion)"},
      {"eye_inner_right", "inner corner of the right eye"},
      {"eye_outer_left", "outer corner of the left eye (exocanthion)"},
      {"eye_outer_right", "outer corner of the right eye"},
      {"nose_tip", "most prominent point of the nose (pronasale)"},
      {"alar_base_left", "where the left nostril's wing meets the cheek (alar crease, subalare)"},
      {"alar_base_right", "where the right nostril's wing meets the cheek"},
      {"cheekbone_left",
       "most prominent point of the left cheekbone (zygion's front, malar eminence)"},
      {"cheekbone_right", "most prominent point of the right cheekbone"},
      {"tragus_left", "the small flap in front of the left ear canal (tragion)"},
      {"tragus_right", "the small flap in front of the right ear canal"},
      {"upper_lip", "midline, the upper lip's edge (labiale superius)"},
      {"lower_lip", "midline, the lower lip's edge (labiale inferius)"},
      {"mouth_corner_left", "left corner of the mouth (cheilion)"},
      {"mouth_corner_right", "right corner of the mouth"},
      {"chin", "most prominent point of the chin (pogonion)"}};
  return e;
}

}  // namespace

const std::vector<std::string>& landmark_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    for (const auto& e : entries()) n.emplace_back(e.name);
    return n;
  }();
  return names;
}

const std::string& landmark_description(const std::string& name) {
  static const std::map<std::string, std::string> d = [] {
    std::map<std::string, std::string> m;
    for (const auto& e : entries()) m[e.name] = e.where;
    return m;
  }();
  static const std::string none;
  const auto it = d.find(name);
  return it == d.end() ? none : it->second;
}

const Vec3d& Landmarks::at(const std::string& name) const {
  const auto it = points.find(name);
  if (it == points.end()) {
    throw ConfigError(file.string(), "landmarks." + name, "missing landmark '" + name + "'");
  }
  return it->second;
}

Landmarks read_landmarks(const std::filesystem::path& path) {
  return parse_landmarks(read_text_file(path, "landmark file"), path);
}

Landmarks parse_landmarks(const std::string& yaml_text, const std::filesystem::path& file) {
  const YamlNode root = parse_yaml(yaml_text, file.string());
  if (!root.is_map()) throw root.error("a landmark file must be a YAML map");
  root.allow_keys({"format", "version", "units", "mesh", "landmarks"});
  const auto f = root.require("format");
  if (f.text() != kLandmarksFormat) {
    throw f.error("expected format '" + std::string(kLandmarksFormat) + "', got '" + f.text() +
                  "'");
  }
  const auto v = root.require("version");
  if (v.integer() != kLandmarksVersion) {
    throw v.error("unsupported version " + v.text() + " (this build reads version " +
                  std::to_string(kLandmarksVersion) + ")");
  }
  constexpr NameTable<LengthUnit, 3> kUnits{
      {{"m", LengthUnit::m}, {"cm", LengthUnit::cm}, {"mm", LengthUnit::mm}}};
  const double scale = metres_per_unit(root.require("units").choose(kUnits, "unit"));
  Landmarks out;
  out.file = file;
  if (root.has("mesh")) out.mesh = root.child("mesh").text();
  const auto l = root.require("landmarks");
  l.expect_map();
  std::vector<std::string_view> allowed;
  for (const auto& n : landmark_names()) allowed.push_back(n);
  l.allow_keys(allowed);
  for (const auto& n : landmark_names()) {
    if (!l.has(n)) {
      throw l.error("missing landmark '" + n + "' (" + landmark_description(n) +
                    "); a version-1 file gives all 20 (docs/landmarks.md)");
    }
    const auto p = l.child(n).vec3();
    out.points[n] = {p[0] * scale, p[1] * scale, p[2] * scale};
  }
  return out;
}

std::string landmarks_yaml(const Landmarks& landmarks, LengthUnit unit,
                           const std::vector<std::string>& comments) {
  std::ostringstream os;
  for (const auto& c : comments) os << "# " << c << "\n";
  os << "format: " << kLandmarksFormat << "\nversion: " << kLandmarksVersion
     << "\nunits: " << to_string(unit) << "\n";
  if (!landmarks.mesh.empty()) os << "mesh: " << landmarks.mesh << "\n";
  os << "landmarks:\n";
  const double s = 1.0 / metres_per_unit(unit);
  for (const auto& n : landmark_names()) {
    const Vec3d& p = landmarks.at(n);
    char buf[160];
    // +0.0 turns a negative zero into "0.000" so mirrored files read the same.
    std::snprintf(buf, sizeof buf, "  %s: [%.3f, %.3f, %.3f]\n", n.c_str(), p.x * s + 0.0,
                  p.y * s + 0.0, p.z * s + 0.0);
    os << buf;
  }
  return os.str();
}

}  // namespace sinew::voxelizer
