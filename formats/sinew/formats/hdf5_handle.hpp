#pragma once
// The base of the HDF5 layer (hdf5_file.hpp): the process-wide lock around every HDF5 call, owned
// HDF5 ids (Handle) and HDF5's error stack read as text. Kept apart from hdf5_file.hpp so that
// the raw-byte checks (hdf5_heap_check.cpp), which hdf5_file.cpp calls, use them without
// including the layer that calls them. hdf5_file.hpp's header says why the lock exists ("Threads").
#include <hdf5.h>

#include <mutex>
#include <string>

namespace sinew::formats::hdf5 {

// The process-wide lock around every HDF5 call (see "Threads" above). Recursive, never destroyed
// (so a handle closed during static destruction or from a thread at exit still finds it).
std::recursive_mutex& library_mutex();
// Holds library_mutex() for its scope (the first line of every function that calls HDF5) and
// switches HDF5's error printing off for the calling thread (quiet_errors()).
class LibraryLock {
 public:
  LibraryLock();
  LibraryLock(const LibraryLock&) = delete;
  LibraryLock& operator=(const LibraryLock&) = delete;

 private:
  std::lock_guard<std::recursive_mutex> guard_;
};

// An owned hid_t, closed with its matching H5*close function on destruction (under the lock).
class Handle {
 public:
  using Closer = herr_t (*)(hid_t);
  Handle() = default;
  Handle(hid_t id, Closer closer) : id_(id), closer_(closer) {}
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  Handle(Handle&& o) noexcept : id_(o.id_), closer_(o.closer_) { o.id_ = -1; }
  Handle& operator=(Handle&& o) noexcept;
  ~Handle() { reset(); }
  // Closes (ignoring the status) and forgets the id.
  void reset();
  // Closes now and reports whether closing worked (a file's close flushes, so it can fail).
  bool close();
  hid_t get() const { return id_; }
  operator hid_t() const { return id_; }  // NOLINT: used as the C API's handle
  bool valid() const { return id_ >= 0; }

 private:
  hid_t id_ = -1;
  Closer closer_ = nullptr;
};

// Silences HDF5's automatic error-stack printing for the calling thread (once per thread: a
// thread-safe HDF5 keeps this setting per thread, a serial one per process). LibraryLock does it,
// so every function here has called it before it calls HDF5.
void quiet_errors();
// HDF5's innermost message on the current error stack as " (HDF5: message)", or "" when the stack
// is empty; clears the stack.
std::string error_detail();

}  // namespace sinew::formats::hdf5
