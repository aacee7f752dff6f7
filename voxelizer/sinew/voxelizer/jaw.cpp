#include "sinew/voxelizer/jaw.hpp"

#include <cmath>

#include "sinew/common/error.hpp"
#include "sinew/voxelizer/face_frame.hpp"

namespace sinew::voxelizer {

JawGeometry jaw_geometry(const Landmarks& l) {
  const FaceFrame f = face_frame(l);
  const auto fail = [&](const std::string& landmark, const std::string& problem) {
    throw ConfigError(l.file.string(), "landmarks." + landmark,
                      "cannot make a mandible: " + problem);
  };
  JawGeometry j;
  j.axis = f.lat(true);
  j.forward = f.fwd;
  j.up = f.up;
  const Vec3d tl = l.at("tragus_left"), tr = l.at("tragus_right");
  j.pivot = 0.5 * (tl + tr) + kCondyleAheadOfTragus * j.forward;
  j.half_condyles = 0.5 * std::abs(dot(tl - tr, j.axis));
  const Vec3d upper = l.at("upper_lip"), lower = l.at("lower_lip");
  if (!(dot(upper - lower, j.up) > 0))
    fail("lower_lip", "the lower lip is not below the upper lip along the face's up");
  j.stomion = 0.5 * (upper + lower);
  if (!(dot(j.stomion - j.pivot, j.up) < -0.02))
    fail("upper_lip", "the lips are not at least 20 mm below the tragi");
  if (!(dot(j.stomion - j.pivot, j.forward) > 0.03))
    fail("upper_lip", "the lips are not at least 30 mm in front of the jaw's axis");
  j.incisal = j.stomion - kLipDepth * j.forward;
  const Vec3d cl = l.at("mouth_corner_left"), cr = l.at("mouth_corner_right");
  const double left = dot(cl - j.stomion, j.axis), right = dot(cr - j.stomion, j.axis);
  if (!(left > 0.005 && right < -0.005))
    fail("mouth_corner_left", "the mouth's corners are not either side of the lips' middle");
  j.half_mouth = 0.5 * (left - right);
  if (j.half_mouth > j.half_condyles)
    fail("mouth_corner_left", "the mouth is wider than the distance between the tragi");
  // The arch: k · lateral² behind the incisal point, reaching the corners' depth minus the lips'.
  const double corner_depth =
      0.5 * (dot(cl - j.stomion, j.forward) + dot(cr - j.stomion, j.forward));  // ≤ 0
  j.arch_curvature = std::max(0.0, -corner_depth) / (j.half_mouth * j.half_mouth);
  return j;
}

bool in_mandible(const JawGeometry& j, const Vec3d& p) {
  return dot(p - j.stomion, j.up) < 0 && dot(p - j.pivot, j.forward) > -kMandibleBehindPivot &&
         std::abs(dot(p - j.pivot, j.axis)) <= j.half_condyles;
}

bool near_occlusal_plane(const JawGeometry& j, const Vec3d& c, double h) {
  return std::abs(dot(c - j.stomion, j.up)) <= 0.5 * h && dot(c - j.pivot, j.forward) > 0 &&
         std::abs(dot(c - j.pivot, j.axis)) <= j.half_condyles;
}

bool in_jaw_cut(const JawGeometry& j, const Vec3d& c, double h, double skull_depth,
                double skin_depth) {
  if (!near_occlusal_plane(j, c, h)) return false;
  const double lateral = dot(c - j.stomion, j.axis);
  const double arch = dot(j.incisal - j.stomion, j.forward) - j.arch_curvature * lateral * lateral;
  if (std::abs(lateral) <= j.half_mouth && dot(c - j.stomion, j.forward) >= arch)
    return true;  // between the lips
  // The vestibule along the teeth: next to the bone, under the cheek's skin.
  return dot(c - j.incisal, j.forward) >= -kArchDepth && skull_depth > -kVestibuleVoxels * h &&
         skin_depth >= kVestibuleVoxels * h;
}

}  // namespace sinew::voxelizer
