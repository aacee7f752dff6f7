#pragma once
// Generated models the size of the paper's Table 2 (Warburton & Maddock 2013), made without the
// voxelizer so they build anywhere (the GPU machine has no CGAL/OpenVDB). Used by bench/ and by the
// CUDA backend tests (small sizes). Materials from the paper's Table 1 (ρ includes its mass
// scaling): stratum corneum 48 MPa, dermis 81.4 kPa, hypodermis 34 kPa, muscle 0.5 MPa, all
// ν = 0.49, ρ = 11,000 kg/m³.
#include <cstdint>

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

}  // namespace sinew::simulator
