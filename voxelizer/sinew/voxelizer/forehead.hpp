#pragma once
// A procedural forehead: closed surface meshes of a skull cap, the skin over it, the left and
// right frontalis muscle sheets and the galea aponeurosis, for sinew-voxelize (docs/forehead.md).
// Deterministic: the same parameters give the same meshes, bit for bit, and the same OBJ text.
//
// Units: millimetres and degrees in ForeheadParams; mesh coordinates in millimetres (the OBJ files
// say so in their header; specs read them with `unit: mm`).
//
// Axes: x to the subject's left-right (the right frontalis at x > 0), y up (y = 0 at the brow
// line's level on the skull), z forward out of the forehead (a camera on +z looks at the face).
//
// Geometry. The skull surface is an ellipsoid (semi-axes A = skull_half_width along x,
// B = skull_vertical_radius along y, C = skull_depth along z, centre at the origin) with two
// superciliary arches added along its normal, parameterised by yaw θ and elevation φ:
//   E(θ, φ) = (A sin θ cos φ, B sin φ, C cos θ cos φ)
//   S(θ, φ) = E + r(θ, φ) n_E,  r = ridge_height · exp(−((φ − ridge_deg)/ridge_width_deg)²)
//             · [exp(−((θ − ridge_yaw_deg)/ridge_spread_deg)²) + exp(−((θ + ridge_yaw_deg)/...)²)]
// with n_E the ellipsoid's outward unit normal. Every other surface is an offset of S along its
// unit normal n (∂S/∂θ × ∂S/∂φ, by central differences): a point at height h over (θ, φ) is
// S + h n. The skin lies at h = t(θ, φ), the soft-tissue thickness
//   t = thickness_mid + (thickness_brow − thickness_mid) exp(−((φ − brow_deg)/brow_width_deg)²)
//       − temple_thinning (θ / patch_half_angle)²,
// over the patch |θ| ≤ patch_half_angle_deg, patch_bottom_deg ≤ φ ≤ patch_top_deg.
// Each frontalis is a sheet between h = muscle_height ± muscle_thickness / 2, from φ =
// muscle_bottom_deg (the brow: its origin) to muscle_top_deg (where it meets the galea: its
// insertion); its medial edge leaves a gap of 2 × medial_gap_bottom mm at the brow widening to
// 2 × medial_gap_top at the top, its lateral edge at |θ| = muscle_lateral_deg. The galea is a band
// between h = galea_height ± galea_thickness / 2 over |θ| ≤ galea_half_angle_deg, from
// galea_bottom_deg (overlapping the muscles' upper ends) to galea_top_deg.
//
// Closed meshes. Each part is a closed, outward-oriented slab: a top and a bottom grid over the
// (θ, φ) rectangle joined by side walls along n. The skin's slab runs from h = t down to
// h = −skin_base_depth, inside the skull cap, whose slab runs from h = 0 over the patch (shrunk by
// 0.05 mm, so that its rim lies just inside the skin's walls) down to h = −skull_cap_depth over the
// patch widened by skull_margin; so skin minus skull is the tissue over the skull within the patch
// (to a sliver 0.05 mm wide and < 0.1 mm tall along the rim). The bottoms (inside the skull) use a
// coarse grid: only the skull cap's bottom and lower walls lie outside the skin.
#include <filesystem>
#include <string>
#include <vector>

#include "sinew/common/math.hpp"
#include "sinew/voxelizer/mesh.hpp"

namespace sinew::voxelizer {

struct ForeheadParams {
  // Skull ellipsoid semi-axes (mm).
  double skull_half_width = 72;        // A, along x
  double skull_vertical_radius = 100;  // B, along y
  double skull_depth = 80;             // C, along z (the forehead's front at z ≈ C)
  // Superciliary arches on the skull (mm, degrees).
  double ridge_height = 1.5;
  double ridge_deg = 3;
  double ridge_width_deg = 6;
  double ridge_yaw_deg = 17;
  double ridge_spread_deg = 14;
  // The patch (degrees): yaw |θ| ≤ half angle, elevation from bottom (below the brow) to top.
  double patch_half_angle_deg = 42;
  double patch_bottom_deg = -6;
  double patch_top_deg = 48;
  // Soft-tissue thickness t (mm) over the skull.
  double thickness_mid = 5.4;
  double thickness_brow = 6.7;
  double brow_deg = 2;
  double brow_width_deg = 7;
  double temple_thinning = 0.25;
  // Frontalis sheets (mm above the skull, degrees).
  double muscle_height = 1.6;     // centre of the sheet above the skull
  double muscle_thickness = 1.0;  // the paper's "≈ 1 mm"
  double muscle_bottom_deg = -3;  // origin: the brow
  double muscle_top_deg = 28;     // insertion: into the galea (1 degree of overlap)
  double medial_gap_bottom = 2;   // mm from the midline to the medial edge at the brow
  double medial_gap_top = 9;      // the same at the top
  double muscle_lateral_deg = 34;
  // Galea aponeurosis (mm above the skull, degrees).
  double galea_height = 1.6;
  double galea_thickness = 1.0;
  double galea_half_angle_deg = 36;
  double galea_bottom_deg = 27;
  double galea_top_deg = 46;
  // Closing the slabs (mm).
  double skin_base_depth = 2;  // the skin's bottom, below the skull surface (inside the cap)
  double skull_cap_depth = 5;  // the skull cap's bottom below its surface
  double skull_margin = 3;     // the cap's bottom extends this far beyond the skin's walls
  // The glide surfaces: closed slabs whose tops lie glide_depth (skull_glide.obj) and
  // glide_depth_coarse (skull_glide_coarse.obj) below the skull surface, over the patch widened by
  // glide_margin, glide_thickness thick, meshed at glide_spacing. The deep layer slides on a top
  // (the specs' sliding condition), so that the nodes inside the skull of the elements the skull
  // surface cuts (at most sqrt(3) h deep) slide with the tissue instead of holding it: the fine one
  // serves voxels up to 1.15 mm, the coarse one voxels up to 2 mm. Shallower is cheaper: the
  // simulator's closest-point search grows with the nodes' distance from the surface.
  double glide_depth = 2;
  double glide_depth_coarse = 3.5;
  double glide_thickness = 3;
  double glide_margin = 12;  // mm beyond the patch: nodes near the patch's rim find its top
  double glide_spacing = 5;  // facets deviate < 0.05 mm from the offset surface
  // Mesh fineness: target edge length (mm) of the closed meshes' top grids (coarse bottoms use
  // 8 × this), and of the open skin surface (the visual surface: fine enough to show wrinkles).
  double spacing = 2;
  double surface_spacing = 0.5;
};

// The five closed meshes, coordinates in mm, plus the skin's top surface alone (open, sampled at
// surface_spacing: the surface shown and exported; it lies on the top of `skin`).
struct ForeheadMeshes {
  TriangleMesh skull;
  TriangleMesh skull_glide;  // the glide surfaces (closed): see glide_depth
  TriangleMesh skull_glide_coarse;
  TriangleMesh skin;
  TriangleMesh skin_surface;
  TriangleMesh frontalis_left;
  TriangleMesh frontalis_right;
  TriangleMesh galea;
};

// Positions useful for specs and scenes (mm), derived from the parameters.
struct ForeheadLandmarks {
  sinew::Vec3d brow_centre;      // skin at θ = 0, φ = brow_deg
  sinew::Vec3d hairline_centre;  // skin at θ = 0, φ = galea_bottom_deg
  double width = 0;              // skin arc length along φ = brow_deg from edge to edge
  double height = 0;             // skin arc length along θ = 0 from patch bottom to top
  sinew::Vec3d lo, hi;           // bounding box of the skin mesh
};

// Throws ConfigError (file "", field = the parameter's name) for values out of range: negative
// sizes, muscle or galea outside the patch, the muscle not under the skin, spacing ≤ 0.
void check_forehead_params(const ForeheadParams& p);

// The skull surface S(θ, φ) and its outward unit normal (angles in degrees, mm).
sinew::Vec3d forehead_skull_point(const ForeheadParams& p, double theta_deg, double phi_deg);
sinew::Vec3d forehead_skull_normal(const ForeheadParams& p, double theta_deg, double phi_deg);
// The soft-tissue thickness t(θ, φ) (mm).
double forehead_thickness(const ForeheadParams& p, double theta_deg, double phi_deg);

// Builds every mesh (checks the parameters first).
ForeheadMeshes make_forehead(const ForeheadParams& p);
ForeheadLandmarks forehead_landmarks(const ForeheadParams& p);

// OBJ text of a mesh: a `#` header (the given comment lines), `v x y z` with 3 decimals, `f a b c`
// (1-based). Deterministic (the C locale's formatting).
std::string obj_text(const TriangleMesh& mesh, const std::vector<std::string>& comments);

// The files make_forehead's meshes go to, by name: skull.obj, skull_glide.obj,
// skull_glide_coarse.obj, skin.obj, skin_surface.obj, frontalis_left.obj, frontalis_right.obj,
// galea.obj.
std::vector<std::string> forehead_file_names();
// Writes every mesh as OBJ into dir (created if needed); returns the paths written. Throws
// IoError when a file cannot be written.
std::vector<std::filesystem::path> write_forehead(const ForeheadParams& p,
                                                  const std::filesystem::path& dir);

}  // namespace sinew::voxelizer
