#pragma once
// Muscle ends on an open skin's free edge with nothing holding them (issue 34, item 2). On a face
// mask (an open mesh, no skull) a muscle whose end reaches the mask's edge pulls that edge in
// instead of moving the face: the frontalis pulled a mask's free top edge down 6.8 mm and raised
// the brows 1.3 mm, without a word. The voxelizer warns, naming the muscle, the end, how far it is
// from the edge and the fix (hold the edge: docs/faces.md, "An open face mask").
//
// An end (the elements the muscle's harmonic fibre field tags as its origin or insertion,
// fibres.hpp) lies on the edge when one of its voxels' centres is within `reach` of a boundary edge
// of the outer mesh (an edge used by one triangle only), and is free there when fewer than half of
// the rim's nodes near it (within `reach` of the edge and 3 `reach` of that voxel) are held (rigid,
// sliding or on the jaw). A closed skin has no boundary edge: no warning.
//
// Units: metres.
#include <string>
#include <vector>

#include "sinew/common/math.hpp"
#include "sinew/formats/model.hpp"
#include "sinew/voxelizer/mesh.hpp"

namespace sinew::voxelizer {

// One muscle's end: its name ("frontalis_left"), which end ("origin" or "insertion") and the
// model's elements that make it.
struct MuscleEnd {
  std::string muscle, end;
  std::vector<formats::Index> elements;
};

struct FreeMuscleEnd {
  std::string muscle, end;
  double edge_distance = 0;           // m, from the end's nearest voxel centre to the free edge
  Vec3d where;                        // that voxel's centre, m
  std::size_t rim = 0, rim_held = 0;  // the edge's nodes near it, and how many of them are held
};

// The ends that are free and on the edge, in the order given.
std::vector<FreeMuscleEnd> free_muscle_ends(const formats::Model& model,
                                            const std::vector<MuscleEnd>& ends,
                                            const TriangleMesh& outer, double reach);

// The voxelizer's warning for one: the muscle, the end, the distance and the fix.
std::string free_muscle_end_warning(const FreeMuscleEnd& end);

}  // namespace sinew::voxelizer
