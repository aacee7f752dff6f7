#pragma once
// Element fields of a results file (/frames/von_mises, /frames/J: one value per hexahedron and
// frame, docs/results-format.md) carried to a surface's vertices, for colouring exports.
//
// Two steps, the usual recovery of a smooth field from element-constant values (one-point
// quadrature makes each element's stress constant):
//  1. nodal averaging: s_n = (1 / |E_n|) Σ_{e ∈ E_n} s_e over the elements E_n that hold node n
//     (all elements have the same volume h³, so this is the volume-weighted average);
//  2. interpolation: a visual vertex embedded in element e at natural coordinates ξ gets
//     s(ξ) = Σ_a N_a(ξ) s_{n_a(e)}, N_a = ⅛ (1 + ξ_a ξ)(1 + η_a η)(1 + ζ_a ζ) (hex8, the same
//     functions that place the vertex, docs/model-format.md); a vertex of the volume's boundary
//     (read_volume_boundary) is a node and takes s_n.
// Source: O. C. Zienkiewicz, R. L. Taylor, The Finite Element Method, vol. 1 (5th ed., 2000),
// §14.2 (nodal averaging of element stresses).
#include <string>
#include <vector>

#include "sinew/postprocess/results_reader.hpp"

namespace sinew::postprocess {

// Per frame (the animation's F complete frames), V values at the animation's vertices of the
// element dataset `dataset` (e.g. "/frames/von_mises", F' × E, F' ≥ F). Needs /mesh/connectivity
// and, for a visual surface, /surfaces/<name>/embedding_element and embedding_local (written by
// sinew-simulate since texture coordinates were added; an older file gets a FormatError saying
// to run the scene again). Throws FormatError naming the file and dataset when one is missing
// (a missing field names the scene's output.fields entry that writes it), has the wrong shape,
// an id out of range or a non-finite value.
std::vector<std::vector<float>> element_field_at_vertices(const std::string& path,
                                                          const SurfaceAnimation& animation,
                                                          const std::string& dataset);

}  // namespace sinew::postprocess
