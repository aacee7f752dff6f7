#pragma once
// The face's own frame from its landmarks (landmarks.hpp), so that what is built from them (the
// rig's muscles, rig_muscles.cpp; the jaw, jaw.hpp) holds for any orientation of the head:
//   lat  (per side): from the other eye's outer corner to this one's (right: towards the
//        subject's right);
//   up:  from the chin to the hairline, made normal to lat;
//   fwd: normal to both, pointing from between the tragi towards the nose's tip.
// Units: those of the landmarks (metres).
#include <string>

#include "sinew/common/math.hpp"
#include "sinew/voxelizer/landmarks.hpp"

namespace sinew::voxelizer {

struct FaceFrame {
  const Landmarks& l;
  Vec3d right, up, fwd;  // unit
  Vec3d at(const std::string& n) const { return l.at(n); }
  Vec3d side(const std::string& n, bool left) const {
    return l.at(n + (left ? "_left" : "_right"));
  }
  Vec3d lat(bool left) const { return left ? -1.0 * right : right; }
};

// Throws ConfigError naming the landmark file and the landmark when the points give no frame (the
// eyes' outer corners less than 1 mm apart; hairline and chin less than 10 mm apart across them).
FaceFrame face_frame(const Landmarks& l);

}  // namespace sinew::voxelizer
