#pragma once
// Everything a model file says about one element or one node, for `sinew-inspect --element N` and
// `--node N` (docs/model-format.md, "sinew-inspect"): where it is, its materials and their
// fractions, its muscles and fibre directions, the constraints of its nodes (rigid; sliding on a
// named surface with the rest distance, the rest triangle and which side of it the node lies
// on), the named sets it belongs to, visual vertices bound to it, and its neighbours in the
// lattice. Positions are printed in mm (and m), fractions as numbers in [0, 1].
#include <string>

#include "sinew/formats/model.hpp"

namespace sinew::formats {

// Assume a valid model (validate_model()); throw ConfigError (file `file`, field "--element" /
// "--node") for an id out of range. The text has several lines and ends with a newline.
std::string describe_element(const Model& model, Index element, const std::string& file = "");
std::string describe_node(const Model& model, Index node, const std::string& file = "");

}  // namespace sinew::formats
