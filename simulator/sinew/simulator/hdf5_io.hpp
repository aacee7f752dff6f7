#pragma once
// Small RAII layer over the HDF5 C API shared by the results writer and the checkpoint (sim-io
// internals; no .cu file includes it). Every failure throws IoError naming the file and the
// dataset; HDF5's own error printing is switched off.
#include <hdf5.h>

#include <cstdint>
#include <string>
#include <vector>

namespace sinew::simulator::h5 {

// An owned hid_t, closed with the matching H5*close on destruction.
class Handle {
 public:
  enum class Kind { file, group, dataset, dataspace, attribute, plist, datatype };
  Handle() = default;
  Handle(hid_t id, Kind kind) : id_(id), kind_(kind) {}
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  Handle(Handle&& o) noexcept : id_(o.id_), kind_(o.kind_) { o.id_ = -1; }
  Handle& operator=(Handle&& o) noexcept;
  ~Handle() { close(); }
  void close();
  hid_t get() const { return id_; }
  operator hid_t() const { return id_; }  // NOLINT: used as the C API's handle
  bool valid() const { return id_ >= 0; }

 private:
  hid_t id_ = -1;
  Kind kind_ = Kind::file;
};

// Silences HDF5's automatic error stack printing (once per process).
void quiet_errors();

Handle create_file(const std::string& path);  // truncates
Handle open_file(const std::string& path, bool writable);
Handle create_group(hid_t loc, const std::string& name, const std::string& file);
Handle open_group(hid_t loc, const std::string& name, const std::string& file);
bool exists(hid_t loc, const std::string& name);

// Fixed-size datasets. `dims` row-major; data of the product of dims.
void write(hid_t loc, const std::string& name, const std::vector<hsize_t>& dims, const double* data,
           const std::string& file);
void write(hid_t loc, const std::string& name, const std::vector<hsize_t>& dims, const float* data,
           const std::string& file);
void write(hid_t loc, const std::string& name, const std::vector<hsize_t>& dims,
           const std::int32_t* data, const std::string& file);
void write(hid_t loc, const std::string& name, const std::vector<hsize_t>& dims,
           const std::int64_t* data, const std::string& file);
void write(hid_t loc, const std::string& name, const std::vector<hsize_t>& dims,
           const std::uint8_t* data, const std::string& file);

// The shape of a dataset.
std::vector<hsize_t> shape(hid_t loc, const std::string& name, const std::string& file);
// Reads a whole dataset, converted to T (double, float, int32, int64, uint8); throws IoError
// when the stored element count differs from `expected` (when expected >= 0).
template <typename T>
std::vector<T> read(hid_t loc, const std::string& name, const std::string& file,
                    std::int64_t expected = -1);

// Extendible datasets of shape (frames, tail...), chunked one frame per chunk.
Handle create_series(hid_t loc, const std::string& name, const std::vector<hsize_t>& tail,
                     hid_t file_type, const std::string& file);
Handle open_dataset(hid_t loc, const std::string& name, const std::string& file);
// Appends one frame (the product of tail values) at index `frame` (== current length).
void append(hid_t dataset, hsize_t frame, hid_t mem_type, const void* data, const std::string& file,
            const std::string& name);
// Shrinks or grows the first dimension to `frames`.
void set_frames(hid_t dataset, hsize_t frames, const std::string& file, const std::string& name);

// Scalar attributes on an object.
void set_attribute(hid_t obj, const std::string& name, const std::string& value,
                   const std::string& file);
void set_attribute(hid_t obj, const std::string& name, double value, const std::string& file);
void set_attribute(hid_t obj, const std::string& name, std::int64_t value, const std::string& file);
std::string string_attribute(hid_t obj, const std::string& name, const std::string& file);
double double_attribute(hid_t obj, const std::string& name, const std::string& file);
std::int64_t int_attribute(hid_t obj, const std::string& name, const std::string& file);
bool has_attribute(hid_t obj, const std::string& name);

void flush(hid_t file, const std::string& path);

}  // namespace sinew::simulator::h5
