#pragma once
// Opening a results file, for this folder's readers (results_reader.cpp, element_fields.cpp) only:
// it exposes the HDF5 layer, which the library's users do not see (sinew::formats is private).
#include <string>

#include "sinew/formats/hdf5_file.hpp"

namespace sinew::postprocess {

// Opens a results file for reading after checking its root attributes `format` and
// `format_version`; throws IoError (no such file), FormatError (not HDF5, not sinew results,
// another version).
formats::hdf5::Handle open_results(const std::string& path);

}  // namespace sinew::postprocess
