#pragma once
// What kind of sinew file an HDF5 file is, read from its root attribute `format`, so that a file
// given in the wrong place (a model to sinew-render, a model as a checkpoint, results as a model)
// is refused with a message saying what it is and what was expected, not a low-level error.
#include <hdf5.h>

#include <string>

#include "sinew/common/error.hpp"

namespace sinew::formats {

// "a sinew model file", "a sinew results file", "a sinew checkpoint", "an HDF5 file with format
// '<name>'" or "an HDF5 file without a sinew format attribute". Never throws.
std::string file_kind(hid_t file, const std::string& path);

// Whether the root attribute `format` is exactly `format_name`. Never throws.
bool has_format(hid_t file, const std::string& path, const std::string& format_name);

// FormatError(path, "format", "this is <file_kind>, not <expected>; <hint>").
FormatError wrong_kind(hid_t file, const std::string& path, const std::string& expected,
                       const std::string& hint);

}  // namespace sinew::formats
