#pragma once
// The jaw of a rigged head (`rig: {jaw: true}`, docs/faces.md "The jaw"): the mandible cut from
// the skull along planes the landmarks define, its temporomandibular axis, and the cut between
// the lips that lets the mouth open. Everything in metres, in the face's frame (face_frame.hpp).
//
//  - Axis and pivot: the condyles sit about 12 mm in front of the tragi (the joint is felt there,
//    in front of the ear: e.g. Gray's Anatomy, 41st ed., ch. 31), so the hinge axis runs through
//    the two tragi moved 12 mm forward, towards the subject's left; the pivot is its midpoint.
//  - Occlusal plane: through the stomion (midway between upper_lip and lower_lip), normal to the
//    face's up. The lips' depth to the incisors: 12 mm (soft-tissue depth at the lips, 10–15 mm in
//    facial reconstruction tables: De Greef et al. 2006, Forensic Sci. Int. 159S, S126–S146);
//    the incisal point rests that far behind the stomion.
//  - Mandible: the skull's held nodes below the occlusal plane, at most 10 mm behind the pivot
//    (the condyle's neck and the ramus's back border) and between the condyles. The ramus above
//    the occlusal plane stays with the skull: a simplification that matters only near the joint,
//    where the rotation moves little.
//  - The cut (oral fissure and vestibule): the voxels whose centre lies within half a voxel of the
//    occlusal plane, in front of the pivot and between the condyles, and either in front of the
//    dental arch between the mouth's corners (the lips) or, along the teeth (at most 45 mm behind
//    the incisal point: the dental arch's depth to the last molars is 40–50 mm in adults), within
//    1.5 voxels of the skull and at least 1.5 voxels under the skin (the vestibule: the cheeks'
//    inner side is not attached to bone along the teeth, and the cheek itself stays whole), are
//    removed, so the lips and the cheeks' deep layer part when the jaw opens. The arch is a
//    parabola through the incisal point and the points 12 mm behind the mouth's corners.
#include <array>
#include <cstdint>
#include <vector>

#include "sinew/common/math.hpp"
#include "sinew/formats/model.hpp"
#include "sinew/voxelizer/landmarks.hpp"

namespace sinew::voxelizer {

inline constexpr double kCondyleAheadOfTragus = 0.012;  // m
inline constexpr double kLipDepth = 0.012;              // m, stomion to incisors
inline constexpr double kMandibleBehindPivot = 0.010;   // m
inline constexpr double kVestibuleVoxels = 1.5;         // voxels from the skull and the skin
inline constexpr double kArchDepth = 0.045;             // m, incisal point to the last molars

struct JawGeometry {
  Vec3d pivot, axis, forward, up;  // m; unit axis (the subject's left), forward, up = fwd × axis
  Vec3d stomion, incisal;          // m
  double half_condyles = 0;        // m, half the distance between the condyles
  double half_mouth = 0;           // m, half the distance between the mouth's corners
  double arch_curvature = 0;       // 1/m: the arch lies k · lateral² behind the incisal point
};

// From the landmarks; throws ConfigError naming the landmark file when the points cannot make a
// mandible (lips not below the tragi, the mouth's corners not either side of the midline, a
// lower lip above the upper one, the mouth not in front of the pivot).
JawGeometry jaw_geometry(const Landmarks& landmarks);

// Whether a held (skull) node at p belongs to the mandible.
bool in_mandible(const JawGeometry& jaw, const Vec3d& p);

// Whether the voxel whose centre is c is cut (h: the voxel size; skull_depth and skin_depth: the
// skull's and the skin's signed distances at c, + inside, − outside, m; called only for voxels
// near the occlusal plane).
bool near_occlusal_plane(const JawGeometry& jaw, const Vec3d& c, double h);
bool in_jaw_cut(const JawGeometry& jaw, const Vec3d& c, double h, double skull_depth,
                double skin_depth);

// The lips' contact pairs (formats::Jaw::lip_pairs) across the cut: `cut` holds the lattice
// coordinates of the removed voxels. Along the lattice axis nearest the face's up, each column of
// removed voxels has a node column at each of its four edges; the node just above the removed run
// and the one just below it, both present, make a pair (upper, lower). Where a node could pair
// twice (columns of different heights meet), the pair across the smaller gap wins; pairs of two
// held nodes (rigid or on the jaw: `held` sorted) are left out. Sorted by upper node.
std::vector<std::array<formats::Index, 2>> lip_pairs(
    const JawGeometry& jaw, const formats::Model& model,
    const std::vector<std::array<std::int32_t, 3>>& cut, const std::vector<formats::Index>& held);

}  // namespace sinew::voxelizer
