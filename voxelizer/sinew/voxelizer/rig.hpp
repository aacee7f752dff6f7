#pragma once
// The muscle rig: closed muscle meshes of the muscles of facial expression built from landmarks on
// the skin (landmarks.hpp), following the skin at anatomical depths and thicknesses, each with its
// fibre field (docs/faces.md gives the anatomy, the sources and the figures).
//
// Two shapes (rig_muscles.cpp gives each muscle's recipe from the landmarks):
//  - a sheet (frontalis, corrugator, zygomatici, levator labii superioris, risorius, depressor
//    anguli oris, mentalis) from its origin O to its insertion I: the centre line C(s) is the skin
//    point closest to (1 − s) O + s I, s in [0, 1]; across it, at width w(s) = (1 − s) w_O + s w_I,
//    the skin points closest to C(s) + t w(s) c(s), t in [−1/2, 1/2], c = n × C′ / |n × C′|; the
//    muscle lies between depths d(s) ∓ thickness / 2 below each skin point along the skin's normal
//    n (interpolated vertex normals), d(s) = (1 − s) d_O + s d_I. Fibres: harmonic from the origin
//    end to the insertion end (fibres.hpp), the two regions being the boxes around the end rows
//    widened by `margin`.
//  - a ring (orbicularis oculi, orbicularis oris) around an axis a through a centre: the skin
//    points where the lines along a through centre + r_a(ρ) cos α M + r_b(ρ) sin α N cross the
//    skin (not the closest ones, which jump between the lips), M the major axis, N = a × M, and
//    radii from the inner ellipse (ρ = 0) to the outer one (ρ = 1); depth and thickness as for a
//    sheet. Fibres: circumferential about a (fibres.hpp).
// Every quad of the closed meshes is split into four triangles around its centre, so a rig built
// from mirror-symmetric landmarks on a mirror-symmetric skin is itself mirror-symmetric.
//
// Units: metres.
#include <string>
#include <vector>

#include "sinew/voxelizer/landmarks.hpp"
#include "sinew/voxelizer/mesh.hpp"
#include "sinew/voxelizer/rig_spec.hpp"
#include "sinew/voxelizer/spec.hpp"

namespace sinew::voxelizer {

// One muscle's recipe, in metres (rig_muscles.cpp).
struct RigRecipe {
  enum class Shape { sheet, ring };
  std::string name;
  Shape shape = Shape::sheet;
  // Sheet: origin and insertion (anywhere near the skin), widths, centre depths below the skin.
  Vec3d origin, insertion;
  double width_origin = 0, width_insertion = 0;
  double depth_origin = 0, depth_insertion = 0;
  // Ring: centre (near the skin), axis (outward, roughly the skin's normal there), major axis
  // direction, inner and outer semi-axes (major, minor). A sheet with an axis (not zero) takes the
  // skin points along it instead of the closest ones.
  Vec3d centre, axis{0, 0, 0}, major;
  double inner_a = 0, inner_b = 0, outer_a = 0, outer_b = 0;
  double thickness = 0;
};

// The recipes of the named rig muscles (rig_muscle_names(); a paired name gives NAME_left and
// NAME_right), depths and thicknesses times depth_scale.
std::vector<RigRecipe> rig_recipes(const Landmarks& landmarks,
                                   const std::vector<std::string>& names, double depth_scale);

struct RigMuscle {
  std::string name;
  TriangleMesh mesh;  // closed, outward oriented, metres
  FibreSpec fibres;
  std::vector<Vec3d> samples;  // points inside the muscle (its grid at 5 depths), for checks
};

// Builds the muscles of the recipes on `skin` (a cleaned mesh, metres). margin: how far the
// harmonic fibres' end regions reach beyond the muscle's end rows (m; about a voxel).
std::vector<RigMuscle> build_rig(const std::vector<RigRecipe>& recipes, const TriangleMesh& skin,
                                 double margin);

// Distance of every landmark from the skin (m), by name.
std::vector<std::pair<std::string, double>> landmark_distances(const Landmarks& landmarks,
                                                               const TriangleMesh& skin);

// The landmarks each moved to its closest point on `skin` (metres; the file, mesh and names kept):
// a first guess picked off the skin (e.g. another head's file scaled to this one) put on it, to be
// corrected by eye on sinew-rig's picture (sinew-rig --snap-landmarks, docs/landmarks.md).
Landmarks snap_landmarks(const Landmarks& landmarks, const TriangleMesh& skin);

// The spec's rig built and checked (needs spec.rig): the landmarks within rig.landmark_tolerance
// of the skin (else ConfigError naming each one and its distance), the muscles built, and
// `message`, empty when at least rig.min_inside of each muscle lies in the tissue, else what
// add_rig_muscles throws: each such muscle, its share, where the rest lies (outside the skin, with
// how far beyond it and nearest which end; in the skull; deeper than tissue_thickness) and what to
// change for that. sinew-rig draws the muscles before it reports the message.
struct CheckedRig {
  std::vector<RigMuscle> muscles;
  std::string message;
};
CheckedRig build_spec_rig(const Spec& spec);

// The spec's rig expanded: loads the landmarks and the skin (and the inner surface), checks every
// landmark is within rig.landmark_tolerance of the skin (ConfigError naming each one that is not
// and its distance), builds the muscles, checks that at least rig.min_inside of each lies in the
// tissue (GeometryError naming each muscle that does not, with its share), and appends them to
// spec.muscles (fibre regions as boxes; meshes as generated sources). No-op without a rig.
void add_rig_muscles(Spec& spec);
// The second half of add_rig_muscles: `built`'s muscles (its message empty) appended to
// spec.muscles; throws ConfigError when the spec's own muscles use one of their names.
void append_rig_muscles(Spec& spec, const CheckedRig& built);

}  // namespace sinew::voxelizer
