#include "sinew/voxelizer/face_frame.hpp"

#include "sinew/common/error.hpp"

namespace sinew::voxelizer {

FaceFrame face_frame(const Landmarks& l) {
  const auto unit = [](const Vec3d& v) { return (1.0 / norm(v)) * v; };
  FaceFrame f{l, {}, {}, {}};
  const Vec3d across = l.at("eye_outer_right") - l.at("eye_outer_left");
  const Vec3d u = l.at("hairline") - l.at("chin");
  // Degenerate points would give no frame (and NaN muscles): say which.
  if (!(norm(across) > 1e-3)) {
    throw ConfigError(l.file.string(), "landmarks.eye_outer_left",
                      "the eyes' outer corners are less than 1 mm apart");
  }
  f.right = unit(across);
  if (!(norm(u - dot(u, f.right) * f.right) > 1e-2)) {
    throw ConfigError(l.file.string(), "landmarks.hairline",
                      "hairline and chin are less than 10 mm apart across the eyes' line");
  }
  f.up = unit(u - dot(u, f.right) * f.right);
  f.fwd = cross(f.up, f.right);
  const Vec3d ahead = l.at("nose_tip") - 0.5 * (l.at("tragus_left") + l.at("tragus_right"));
  if (dot(f.fwd, ahead) < 0) f.fwd = -1.0 * f.fwd;
  return f;
}

}  // namespace sinew::voxelizer
