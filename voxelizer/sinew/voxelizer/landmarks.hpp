#pragma once
// Facial landmarks: named points on the skin from which the muscle rig is built (rig.hpp).
// File format `sinew-landmarks` version 1 (docs/landmarks.md gives the schema and how to pick the
// points on a new head):
//
//   format: sinew-landmarks
//   version: 1
//   units: mm                 # m, cm or mm: unit of every coordinate below
//   mesh: head.obj            # optional: the skin mesh the points were picked on (informational)
//   landmarks:
//     hairline: [0, 78.2, 84.1]
//     ...                     # every name of landmark_names(), each once, nothing else
//
// Axes: those of the skin mesh (any orientation: the rig derives the face's frame from the
// points). Left and right are the subject's own.
// read_landmarks/parse_landmarks are the format's one validator: unknown keys, a missing or
// unknown landmark, a wrong format name or version and non-finite coordinates throw ConfigError
// naming the file, the key path and the line.
#include <array>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "sinew/common/math.hpp"
#include "sinew/voxelizer/mesh.hpp"

namespace sinew::voxelizer {

inline constexpr const char* kLandmarksFormat = "sinew-landmarks";
inline constexpr int kLandmarksVersion = 1;

// The 20 landmarks of version 1, in the order files list them.
const std::vector<std::string>& landmark_names();
// One line per landmark: where it is on the face (docs/landmarks.md's table uses the same text).
const std::string& landmark_description(const std::string& name);

struct Landmarks {
  std::filesystem::path file;           // where they were read from ("" when built in code)
  std::map<std::string, Vec3d> points;  // name -> position, metres
  std::string mesh;                     // the file's `mesh` entry, if any

  // The point of a landmark; throws ConfigError naming the file when it is missing.
  const Vec3d& at(const std::string& name) const;
};

Landmarks read_landmarks(const std::filesystem::path& path);
Landmarks parse_landmarks(const std::string& yaml_text, const std::filesystem::path& file);

// The file text of `landmarks` in `unit` (3 decimals of that unit), with an optional comment
// header; parse_landmarks reads it back to within half a unit of the last decimal.
std::string landmarks_yaml(const Landmarks& landmarks, LengthUnit unit,
                           const std::vector<std::string>& comments = {});

}  // namespace sinew::voxelizer
