// Each rig muscle's recipe from the landmarks: where it starts and ends, how wide, how deep, how
// thick. Anatomy (origins, insertions, layering) from Gray's Anatomy (41st ed., ch. 29, "Face and
// scalp"); depths and thicknesses in mm, chosen within the ranges docs/faces.md cites. Positions
// are built in the face's own frame (face_frame.hpp), so the recipes hold for any orientation of
// the head; offsets below are in mm along its directions.
#include <algorithm>
#include <cmath>

#include "sinew/common/error.hpp"
#include "sinew/voxelizer/face_frame.hpp"
#include "sinew/voxelizer/rig.hpp"

namespace sinew::voxelizer {
namespace {

constexpr double kMm = 1e-3;

Vec3d unit(const Vec3d& v) {
  return (1.0 / norm(v)) * v;
}
Vec3d lerp(const Vec3d& a, const Vec3d& b, double t) {
  return a + t * (b - a);
}

RigRecipe sheet(std::string name, Vec3d o, Vec3d i, double w_o, double w_i, double d_o, double d_i,
                double thickness) {
  RigRecipe r;
  r.name = std::move(name);
  r.shape = RigRecipe::Shape::sheet;
  r.origin = o;
  r.insertion = i;
  r.width_origin = w_o * kMm;
  r.width_insertion = w_i * kMm;
  r.depth_origin = d_o * kMm;
  r.depth_insertion = d_i * kMm;
  r.thickness = thickness * kMm;
  return r;
}

RigRecipe ring(std::string name, Vec3d centre, Vec3d axis, Vec3d major, double a_in, double b_in,
               double a_out, double b_out, double depth, double thickness) {
  RigRecipe r;
  r.name = std::move(name);
  r.shape = RigRecipe::Shape::ring;
  r.centre = centre;
  r.axis = unit(axis);
  r.major = unit(major);
  r.inner_a = a_in;
  r.inner_b = b_in;
  r.outer_a = a_out;
  r.outer_b = b_out;
  r.depth_origin = r.depth_insertion = depth * kMm;
  r.thickness = thickness * kMm;
  return r;
}

// One side's (or the midline's) recipe of a rig muscle.
RigRecipe recipe(const FaceFrame& f, const std::string& base, bool left) {
  const std::string name = base + (left ? "_left" : "_right");
  const Vec3d lat = f.lat(left), up = f.up;
  const Vec3d mouth_corner = f.side("mouth_corner", left);
  // The modiolus, where the cheek's muscles meet lateral to the mouth's corner.
  const Vec3d modiolus = mouth_corner + 8 * kMm * lat;
  if (base == "frontalis") {
    // From the galea 12 mm above the hairline's height down into the skin of the brow.
    const Vec3d brow = f.side("brow_centre", left);
    const double rise = dot(f.at("hairline") - f.at("glabella"), up);
    const double width = 1.5 * norm(brow - f.at("glabella")) / kMm;  // mm
    // Up the forehead's slope (glabella to hairline), not straight up: the skin curves back, and a
    // chord straight up would end in front of the skin, its closest skin points crowded below the
    // hairline.
    const Vec3d slope = (1.0 / rise) * (f.at("hairline") - f.at("glabella"));
    return sheet(name, brow + (rise + 12 * kMm) * slope, brow + 4 * kMm * up, width, width, 3.5,
                 3.5, 1.2);
  }
  if (base == "corrugator") {
    // From the medial brow ridge (deep) up and out into the skin above the brow's middle.
    const Vec3d g = f.at("glabella");
    const double reach = norm(f.side("brow_centre", left) - g);
    return sheet(name, g + 5 * kMm * lat - 2 * kMm * up, g + 0.8 * reach * lat + 6 * kMm * up, 9, 8,
                 5.0, 4.6, 1.2);
  }
  if (base == "zygomaticus_major") {
    // From the zygomatic bone, behind the cheekbone's point, to the modiolus.
    const Vec3d cheek = f.side("cheekbone", left);
    const Vec3d o = lerp(cheek, f.side("tragus", left), 0.3) - 5 * kMm * up;
    return sheet(name, o, modiolus, 10, 8, 6.0, 4.5, 2.0);
  }
  if (base == "zygomaticus_minor") {
    // From the cheekbone's front, medial to the major, to the upper lip's lateral part.
    const Vec3d o = f.side("cheekbone", left) - 8 * kMm * lat + 2 * kMm * up;
    const Vec3d i = lerp(f.at("upper_lip"), mouth_corner, 0.55) + 3 * kMm * up;
    return sheet(name, o, i, 7, 6, 5.5, 3.5, 1.5);
  }
  if (base == "levator_labii_superioris") {
    // From the infraorbital margin down into the upper lip beside the nose.
    const Vec3d o = lerp(f.side("eye_inner", left), f.side("eye_outer", left), 0.35) - 9 * kMm * up;
    const Vec3d i = f.side("alar_base", left) + 2 * kMm * lat - 9 * kMm * up;
    return sheet(name, o, i, 12, 9, 5.5, 3.5, 1.8);
  }
  if (base == "risorius") {
    // From the fascia over the parotid (towards the ear) to the modiolus; superficial. It runs
    // horizontally (Gray's), at the mouth's corner's height: the tragus lies level with the eyes.
    const Vec3d towards_ear = f.side("tragus", left) - mouth_corner;
    const Vec3d o = mouth_corner + 0.55 * (towards_ear - dot(towards_ear, up) * up);
    return sheet(name, o, modiolus, 8, 6, 3.0, 3.0, 1.0);
  }
  if (base == "depressor_anguli_oris") {
    // From the mandible's lower border, below and lateral to the mouth, up to the modiolus.
    const double drop = dot(mouth_corner - f.at("chin"), up);
    const Vec3d o = mouth_corner + 6 * kMm * lat - drop * up;
    return sheet(name, o, modiolus - 2 * kMm * up, 18, 6, 3.5, 3.5, 1.5);
  }
  if (base == "orbicularis_oculi") {
    // Palpebral and orbital parts: a ring from the eyelids' opening out over the orbit's rim.
    const Vec3d in = f.side("eye_inner", left), out = f.side("eye_outer", left);
    const double e = 0.5 * norm(out - in);
    // The orbit's skin faces forward and a little outward.
    return ring(name, lerp(in, out, 0.5), f.fwd + 0.35 * lat, out - in, 1.0 * e, 0.45 * e, 2.1 * e,
                1.7 * e, 2.0, 1.0);
  }
  if (base == "orbicularis_oris") {
    // Around the mouth: from the lips' red margin out to the nasolabial region and the chin.
    const Vec3d l = f.at("mouth_corner_left"), r = f.at("mouth_corner_right");
    const Vec3d c = 0.25 * (l + r + f.at("upper_lip") + f.at("lower_lip"));
    const double m = 0.5 * norm(r - l), v = 0.5 * norm(f.at("upper_lip") - f.at("lower_lip"));
    return ring(base, c, f.fwd, r - l, 0.8 * m, 0.3 * v, m + 8 * kMm, v + 9 * kMm, 3.5, 3.0);
  }
  // mentalis: from the incisive fossa below the lower lip (deep) down to the chin's skin.
  const Vec3d o = lerp(f.at("lower_lip"), f.at("chin"), 0.3);
  RigRecipe r = sheet(base, o, f.at("chin") - 4 * kMm * up, 16, 20, 7.0, 4.0, 3.0);
  r.axis = f.fwd;
  return r;
}

}  // namespace

std::vector<RigRecipe> rig_recipes(const Landmarks& landmarks,
                                   const std::vector<std::string>& names, double depth_scale) {
  const FaceFrame f = face_frame(landmarks);
  std::vector<RigRecipe> out;
  for (const auto& base : rig_muscle_names()) {
    if (std::find(names.begin(), names.end(), base) == names.end()) continue;
    const bool midline = base == "orbicularis_oris" || base == "mentalis";
    for (const bool left : {true, false}) {
      if (midline && !left) continue;
      RigRecipe r = recipe(f, base, left);
      r.depth_origin *= depth_scale;
      r.depth_insertion *= depth_scale;
      r.thickness *= depth_scale;
      out.push_back(std::move(r));
    }
  }
  return out;
}

}  // namespace sinew::voxelizer
