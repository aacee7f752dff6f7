#pragma once
// Generated models the size of the paper's Table 2 (Warburton & Maddock 2013), made without the
// voxelizer so they build anywhere (the GPU machine has no CGAL/OpenVDB). Used by bench/ and by the
// CUDA backend tests (small sizes). Materials from the paper's Table 1 (ρ includes its mass
// scaling): stratum corneum 48 MPa, dermis 81.4 kPa, hypodermis 34 kPa, muscle 0.5 MPa, all
// ν = 0.49, ρ = 11,000 kg/m³.
#include <cstdint>
#include <string>

#include "sinew/formats/model.hpp"

namespace sinew::simulator {

// Skin block: nx × ny × nz voxels of side h (default 120 × 120 × 9, h = 0.25 mm: 129,600
// elements, 146,410 nodes), layers from the bottom: hypodermis, dermis 1.8 mm, stratum corneum
// 0.02 mm (cut voxels get volume fractions). Node sets as formats::make_box_model.
formats::Model make_skin_block_model(int nx = 120, int ny = 120, int nz = 9, double h = 0.25e-3);

// Forehead-like slab over a skull-like surface: nx × ny × nz voxels of side h (default 710 × 178 ×
// 4, h = 0.5 mm: 505,520 elements, 636,345 nodes), layers from the bottom: muscle tissue 0.5 mm,
// hypodermis to 1 mm, dermis to 1.98 mm, stratum corneum. Two muscles (left and right frontalis
// boxes in the bottom layer, fibres along +y). Every bottom node (≈ 20%) slides on a cylindrical
// "skull" surface below the slab (a cylinder about an axis along y, 0.25 h below the bottom at the
// middle and 2.25 h at the sides), kept at its rest distance. Node set "y_max" is the natural rigid
// edge.
formats::Model make_forehead_model(int nx = 710, int ny = 178, int nz = 4, double h = 0.5e-3);

// Multi-material soft body (Armadillo-like: body, head, ears, arms, legs, tail as ellipsoids,
// voxel side h): at scale 1.085, 15,110 elements and 19,612 nodes. Three nested materials by
// distance from the body centre (stiff core E = 400 kPa, 200 kPa, soft skin 100 kPa; ν = 0.45,
// ρ = 1000). Node set "feet": the lowest nodes of the legs.
formats::Model make_soft_body_model(double scale = 1.085, double h = 2e-3);

// ---- Sample models (sinew-sample-model, data/scenes/, docs/sample-models.md) ------------------
// Additive: the models above are left exactly as they are; these add what a scene and the renderer
// need.

// Adds a visual surface `name` made of the volume's boundary: every element face that belongs to
// one element only, split into two triangles (counter-clockwise seen from outside), its vertices
// the boundary nodes (shared between faces) embedded at their corner of an element holding them
// (natural coordinates ±1, so a vertex moves exactly with its node). Faces whose four nodes all lie
// in the node set `skip_set` are left out (e.g. "z_min", a fixed base nobody sees); "" keeps every
// face. Throws ConfigError when `skip_set` is not a node set of the model or the name is taken.
void add_boundary_visual_surface(formats::Model& model, const std::string& name = "skin",
                                 const std::string& skip_set = "");

// The skin block of make_skin_block_model (same arguments) as a sample model: its visual surface
// "skin" (add_boundary_visual_surface without the bottom face z_min) and node set "press": the top
// nodes (k = nz) of a centred square patch of press_width voxels per side (lattice i and j within
// press_width / 2 of the centre; 0: nx / 10 rounded, at least 1): 13 × 13 = 169 nodes, 3 mm × 3 mm,
// at the default size. The base z_min is not made rigid here; the scene holds it.
formats::Model make_skin_block_sample_model(int nx = 120, int ny = 120, int nz = 9,
                                            double h = 0.25e-3, int press_width = 0);

// A soft body for scenes under gravity, made like make_soft_body_model (same arguments, parts,
// materials and node set "feet") but able to stand: there the legs end below the belly and touch
// the body along edges only (a mechanism once the feet are held), so here the legs (radius 3.2)
// stand further in (x = ±10, y = ±6), reach up into the body, and end on flat pads cut by the
// floor z = −28 (reference units); the arms sit 1 closer to the body; only the largest
// face-connected piece is kept. Default size: 16,354 elements, 20,992 nodes, 162 × 64 × 106 mm,
// 0.1308 kg. Visual surface "skin": the whole boundary (add_boundary_visual_surface).
formats::Model make_soft_body_sample_model(double scale = 1.085, double h = 2e-3);

// Σ over elements and materials of fraction · ρ · h³: the mass, kg, of a model (density as in the
// file, before any mass scaling).
double model_mass(const formats::Model& model);

}  // namespace sinew::simulator
