#include "sinew/voxelizer/rig_spec.hpp"

#include <algorithm>

#include "sinew/common/error.hpp"
#include "sinew/common/yaml_reader.hpp"
#include "sinew/voxelizer/mesh.hpp"

namespace sinew::voxelizer {

const std::vector<std::string>& rig_muscle_names() {
  // The sphincters first: a later muscle overrides an earlier one where they overlap, and the
  // cheek's muscles end in the orbicularis oris at the modiolus (their insertions must keep
  // their voxels).
  static const std::vector<std::string> names{"orbicularis_oris",
                                              "orbicularis_oculi",
                                              "frontalis",
                                              "corrugator",
                                              "zygomaticus_major",
                                              "zygomaticus_minor",
                                              "levator_labii_superioris",
                                              "risorius",
                                              "depressor_anguli_oris",
                                              "mentalis"};
  return names;
}

RigSpec parse_rig_spec(const YamlNode& n, const std::filesystem::path& folder, LengthUnit units) {
  n.expect_map();
  n.allow_keys({"landmarks", "muscles", "material", "reference_stress", "depth_scale",
                "landmark_tolerance", "min_inside", "jaw"});
  RigSpec r;
  r.field = n.path();
  const auto l = n.require("landmarks");
  if (!l.is_scalar() || l.text().empty()) throw l.error("expected the landmark file's path");
  r.landmarks = std::filesystem::path(l.text());
  if (r.landmarks.is_relative()) r.landmarks = (folder / r.landmarks).lexically_normal();
  const auto& known = rig_muscle_names();
  if (!n.has("muscles") || (n.child("muscles").is_scalar() && n.child("muscles").text() == "all")) {
    r.muscles = known;
  } else {
    const auto m = n.child("muscles");
    if (!m.is_sequence()) throw m.error("expected 'all' or a list of muscle names");
    for (const auto& item : m.items()) {
      const std::string name = item.text();
      if (std::find(known.begin(), known.end(), name) == known.end()) {
        std::string list;
        for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
        throw item.error("unknown rig muscle '" + name + "' (known: " + list + ")");
      }
      if (std::find(r.muscles.begin(), r.muscles.end(), name) != r.muscles.end()) {
        throw item.error("muscle '" + name + "' listed twice");
      }
      r.muscles.push_back(name);
    }
    if (r.muscles.empty()) throw m.error("list at least one muscle (or leave out the rig)");
  }
  if (n.has("material")) {
    const auto mat = n.child("material");
    if (!mat.is_scalar() || mat.text().empty()) throw mat.error("expected a material name");
    r.material = mat.text();
  }
  if (n.has("reference_stress")) r.reference_stress = n.child("reference_stress").positive();
  if (n.has("depth_scale")) {
    r.depth_scale = n.child("depth_scale").positive();
    if (r.depth_scale > 5) throw n.child("depth_scale").error("must be in (0, 5]");
  }
  if (n.has("landmark_tolerance")) {
    r.landmark_tolerance = n.child("landmark_tolerance").positive() * metres_per_unit(units);
  }
  if (n.has("min_inside")) {
    r.min_inside = n.child("min_inside").number();
    if (!(r.min_inside > 0 && r.min_inside <= 1)) {
      throw n.child("min_inside").error("must be in (0, 1]");
    }
  }
  if (n.has("jaw")) r.jaw = n.child("jaw").boolean();
  return r;
}

}  // namespace sinew::voxelizer
