#pragma once
// The one HDF5 layer of sinew: RAII handles over the HDF5 C API and typed reads and writes of
// datasets and attributes. The model file (model_file.cpp), the results writer, the checkpoint,
// the results reader and the tools all go through it. Host only: no .cu file includes it.
//
// Errors are typed exceptions (common/error.hpp) naming the file, the dataset or attribute path
// and the problem, with HDF5's innermost message appended as " (HDF5: ...)" when it has one:
//   IoError      a file that cannot be created, opened, written, flushed or closed;
//   FormatError  a file whose contents are not what the caller asked for: a missing group,
//                dataset or attribute, a wrong dtype or shape, data that cannot be read back.
// A system error inside HDF5's file driver is reported by its reason alone ("cannot write the
// dataset: no space left on the device (disk full)"), not HDF5's raw driver text. A file whose
// close fails (a full disk at the final flush) does not crash the process at exit: the library's
// own atexit clean-up, which segfaults on such a file in HDF5 1.10, is then skipped.
// HDF5's own printing of its error stack is switched off (quiet_errors(), done by every function
// here for its thread), so a corrupt file gives one exception and no noise.
//
// Paths are absolute within the file ("/mesh/connectivity"); an attribute is named in errors as
// its object's path joined with its name ("/format", "/mesh/units").
//
// Files written here carry no object time stamps, so the same data give byte-identical files.
//
// Threads: every function here and every Handle close (reset(), close(), the destructor, move
// assignment) holds library_mutex() while it is inside HDF5, so no two threads of the process are
// ever in the HDF5 library at once, whatever its build. This is what lets several runs share a
// process (sinew-sweep --concurrent K) and the simulator write frames on a background thread
// (frame_writer.hpp) with the serial HDF5 of Ubuntu (1.10, not built thread-safe), where two
// threads in HDF5 at once corrupt its global state (ID table, metadata cache, error stack). On a
// thread-safe build (Debian's) HDF5's own global lock serialises the same way, so nothing is lost:
// HDF5 I/O never overlaps across threads either way; a frame write waits for another run's read.
// The lock is taken once per call (recursive: the functions here call each other) and is held
// through the whole call, so HDF5's error stack, global on a serial build, is read by the thread
// that filled it. Code outside formats/ makes no HDF5 call of its own (only the tests do), so
// nothing bypasses the lock; hdf5_heap_check.cpp takes it too.
#include <hdf5.h>

#include <cstdint>
#include <string>
#include <vector>

#include "sinew/formats/hdf5_handle.hpp"

namespace sinew::formats::hdf5 {

// Element types T the typed functions take: double (float64), float (float32), std::int32_t,
// std::int64_t, std::uint8_t. Stored little-endian (H5T_IEEE_F64LE, H5T_STD_I32LE, ...).

// ---- Files ------------------------------------------------------------------------------------

// Whether `path` carries the HDF5 signature (false for a missing or unreadable file, and for
// anything but a regular file: a FIFO or a device is not read).
bool is_hdf5(const std::string& path);
// Creates (truncates) `path`; errors name `display` (default: path), e.g. the final name of a file
// written to a temporary first. IoError on failure.
Handle create_file(const std::string& path, const std::string& display = {});
// Opens an existing file; IoError when it cannot be opened as HDF5 (missing, unreadable, not HDF5).
Handle open_file(const std::string& path, bool writable);
// Opens an existing file read-only, telling the failures apart: IoError when the file cannot be
// read at all ("cannot open: <reason>"), FormatError when it is not HDF5 ("not an HDF5 file (no
// HDF5 signature found)") or is damaged ("cannot open as HDF5, the file is truncated or corrupt").
Handle open_checked(const std::string& path);
// Closes a file now, reporting a failed close (which flushes) as IoError naming `display`.
void close_file(Handle& file, const std::string& display);
void flush(hid_t file, const std::string& path);

// ---- Groups -----------------------------------------------------------------------------------

// ordered: the group records link creation order, so members() lists in the order written.
Handle create_group(hid_t loc, const std::string& name, const std::string& file,
                    bool ordered = false);
Handle open_group(hid_t loc, const std::string& name, const std::string& file);
// Whether the link `name` exists; a missing intermediate group gives false, not an error.
bool exists(hid_t loc, const std::string& name);
// The names of a group's members: in creation order when the group tracks it, else by name.
// FormatError when the group is missing or cannot be listed.
std::vector<std::string> members(hid_t loc, const std::string& group, const std::string& file);

// ---- Datasets: writing ------------------------------------------------------------------------

// A fixed-size dataset of shape `dims` (row-major; empty dims: a scalar) from the product of dims
// values at `data` (may be null when the product is 0).
template <typename T>
void write(hid_t loc, const std::string& name, const std::vector<hsize_t>& dims, const T* data,
           const std::string& file);
// Variable-length UTF-8 strings: a 1-D dataset of values.size(), or one scalar string.
void write_strings(hid_t loc, const std::string& name, const std::vector<std::string>& values,
                   const std::string& file);
void write_string(hid_t loc, const std::string& name, const std::string& value,
                  const std::string& file);

// ---- Datasets: reading ------------------------------------------------------------------------

Handle open_dataset(hid_t loc, const std::string& name, const std::string& file);
// The dims of a dataset (empty for a scalar).
std::vector<hsize_t> shape(hid_t loc, const std::string& name, const std::string& file);
// Reads a whole dataset of any shape, flattened and converted to T by HDF5; FormatError when the
// element count differs from `expected` (when expected >= 0) or the data cannot be read.
template <typename T>
std::vector<T> read(hid_t loc, const std::string& name, const std::string& file,
                    std::int64_t expected = -1);
// Strict reads: the stored dtype must be exactly T's (class, size, signedness) and the shape
// exactly (n) when cols == 0, else (n, cols); flattened row-major. FormatError otherwise:
// "missing dataset", "wrong dtype, expected int32", "wrong shape (36, 7), expected (n, 8)".
// Row counts past 2^31 - 1 are refused (sinew ids are 32-bit), as is a failed allocation.
template <typename T>
std::vector<T> read_array(hid_t loc, const std::string& name, const std::string& file,
                          hsize_t cols = 0);
// A scalar dataset of exactly T's dtype.
template <typename T>
T read_scalar(hid_t loc, const std::string& name, const std::string& file);
// A 1-D string dataset / a scalar string dataset; variable-length or fixed-length (NUL- or
// space-padded, as other tools may write them).
std::vector<std::string> read_strings(hid_t loc, const std::string& name, const std::string& file);
std::string read_string(hid_t loc, const std::string& name, const std::string& file);

// ---- Extendible datasets: shape (frames, tail...), chunked one frame per chunk ---------------

template <typename T>
Handle create_series(hid_t loc, const std::string& name, const std::vector<hsize_t>& tail,
                     const std::string& file);
// Appends one frame (the product of tail values of T) at index `frame` (== current length).
template <typename T>
void append(hid_t dataset, hsize_t frame, const T* data, const std::string& file,
            const std::string& name);
// Shrinks or grows the first dimension to `frames`.
// Where a chunked dataset's chunks lie in the file (bytes [address, address + size)); empty for
// other layouts. FormatError when one lies past the file's end. A damaged chunk index would have
// HDF5 free space it does not own when a series shrinks, and crash closing the file.
struct ChunkExtent {
  haddr_t address = 0;
  hsize_t size = 0;
  std::string dataset;
};
std::vector<ChunkExtent> chunk_extents(hid_t dataset, const std::string& file,
                                       const std::string& name);
// FormatError (naming both datasets) when two of the extents overlap.
void check_disjoint(std::vector<ChunkExtent> extents, const std::string& file);
void set_frames(hid_t dataset, hsize_t frames, const std::string& file, const std::string& name);

// A virtual dataset (HDF5 VDS) `name` of shape (tail...) that shows frame `frame` of the series
// `source` in the same file: no data of its own, so readers that take whole datasets only (meshio,
// the XDMF index) can name one frame. Intermediate groups are created. IoError on failure.
void create_frame_view(hid_t loc, const std::string& name, const std::string& source, hsize_t frame,
                       const std::string& file);

// ---- Attributes (one value each) -------------------------------------------------------------

// String attributes are fixed-length NUL-padded by default; variable-length UTF-8 when asked
// (the model file's root attribute `format`). Writing replaces an existing attribute.
enum class StringKind { fixed, variable };
void set_attribute(hid_t obj, const std::string& name, const std::string& value,
                   const std::string& file, StringKind kind = StringKind::fixed);
void set_attribute(hid_t obj, const std::string& name, double value, const std::string& file);
void set_attribute(hid_t obj, const std::string& name, std::int64_t value, const std::string& file);
void set_attribute(hid_t obj, const std::string& name, std::int32_t value, const std::string& file);
bool has_attribute(hid_t obj, const std::string& name);
// FormatError when missing ("missing attribute"), not one value of the right class ("must be one
// string", "must be one integer", "must be one number") or unreadable.
std::string string_attribute(hid_t obj, const std::string& name, const std::string& file);
double double_attribute(hid_t obj, const std::string& name, const std::string& file);
std::int64_t int_attribute(hid_t obj, const std::string& name, const std::string& file);

}  // namespace sinew::formats::hdf5
