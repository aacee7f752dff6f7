#pragma once
// The `rig:` section of a voxelizer spec (docs/faces.md): build the muscles of facial expression
// from a landmark file (landmarks.hpp) instead of listing muscle meshes. Read by parse_rig_spec
// (rig_spec.cpp), expanded into spec muscles by add_rig_muscles (rig.hpp) when the model is built.
//
//   rig:
//     landmarks: head_landmarks.yaml   # sinew-landmarks file, relative to the spec's folder
//     muscles: all                     # or a list of names from rig_muscle_names()
//     material: muscle                 # passive material of every rig muscle (default muscle)
//     reference_stress: 5.0e6          # Pa, sigma_ref of every rig muscle (default 5e6)
//     depth_scale: 1                   # multiplies every muscle's depth and thickness (default 1)
//     landmark_tolerance: 2            # spec units: a landmark farther off the skin is an error
//     min_inside: 0.9                  # fraction of each muscle that must lie in the tissue
//     jaw: true                        # the mandible apart from the skull (jaw.hpp; default false)
//
// Units: lengths in this struct in metres.
#include <filesystem>
#include <string>
#include <vector>

namespace sinew {
class YamlNode;
}

namespace sinew::voxelizer {

enum class LengthUnit;

struct RigSpec {
  std::filesystem::path landmarks;
  std::vector<std::string> muscles;  // names from rig_muscle_names(); paired ones mean both sides
  std::string material = "muscle";
  double reference_stress = 5e6;  // Pa
  double depth_scale = 1.0;
  double landmark_tolerance = 0.002;  // m
  double min_inside = 0.9;
  bool jaw = false;  // cut the mandible from the skull (needs `inner`): the model's /jaw
  std::string field = "rig";
};

// The rig's muscles by name, in build order (a later one overrides an earlier one where they
// overlap): orbicularis_oris (one, across the midline), orbicularis_oculi, frontalis, corrugator,
// zygomaticus_major, zygomaticus_minor, levator_labii_superioris, risorius, depressor_anguli_oris
// (each a left and right muscle, NAME_left and NAME_right), mentalis (one, across the midline).
const std::vector<std::string>& rig_muscle_names();

// Reads the section. folder resolves the landmark path; units converts landmark_tolerance. Throws
// ConfigError naming the key for unknown keys, unknown muscle names and values out of range.
RigSpec parse_rig_spec(const YamlNode& n, const std::filesystem::path& folder, LengthUnit units);

}  // namespace sinew::voxelizer
