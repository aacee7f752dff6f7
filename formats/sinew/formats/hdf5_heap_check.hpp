#pragma once
// Checks of HDF5's global heap before HDF5 reads variable-length strings from it (used by
// hdf5_file.cpp's string readers). The global heap is the one part of an HDF5 file that no
// checksum covers, even in the 1.8+ format, and HDF5 1.10 trusts it: a damaged heap object size
// or index, or a damaged string descriptor in contiguous raw data, makes H5Dread / H5Aread copy
// from or to the wrong memory (seen: a segfault in H5HG_read from one flipped byte of a model
// file). These functions read the file's bytes themselves and throw FormatError naming the
// dataset or attribute when what HDF5 would follow is inconsistent.
//
// Global heap collection (HDF5 file format spec, "Global Heap"): "GCOL", version 1, 3 reserved
// bytes, the collection size (length-sized, header included), then objects: index (2 bytes),
// reference count (2), reserved (4), size (length-sized), data padded to a multiple of 8; the
// free-space object has index 0 and its size counts its header.
#include <hdf5.h>

#include <string>

namespace sinew::formats::hdf5 {

// Before reading a dataset of variable-length strings: its layout must be contiguous (the only one
// whose raw descriptors can be read without HDF5 following them), and every descriptor (length,
// collection address, object index) must name an object of exactly that length in a well-formed
// collection inside the file. FormatError otherwise.
void check_vlen_dataset(hid_t dataset, const std::string& file, const std::string& name);
// Before reading the variable-length string attribute `attribute` of `obj`, whose descriptor lies
// in an object header: every global heap collection in the file (found by its signature) must be
// well-formed, and, when the header is version 1 (no checksum; a version 2 header is checksummed
// and HDF5 refuses a damaged one), the attribute's reference must name an object of its length.
// FormatError otherwise, naming `where`.
void check_global_heaps(hid_t obj, const std::string& file, const std::string& where,
                        const std::string& attribute);

// Before HDF5 looks at any attribute of `obj` (H5Aexists and H5Aopen decode every attribute
// message of its header): when the header is version 1 (no checksum), every attribute message's
// parts (name, datatype, dataspace, value = the datatype's size × the dataspace's points) must fit
// inside the message. HDF5 1.10 copies the value from where the sizes say, out of bounds when
// they are damaged (fuzz cases: a segfault in H5Aexists, or 21 s clearing a buffer for a
// descriptor read from other bytes). FormatError naming `where` otherwise.
void check_attribute_messages(hid_t obj, const std::string& file, const std::string& where);

}  // namespace sinew::formats::hdf5
