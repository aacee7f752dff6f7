#include "sinew/formats/hdf5_handle.hpp"

#include <atomic>
#include <cstdlib>

namespace sinew::formats::hdf5 {

namespace {

herr_t innermost(unsigned, const H5E_error2_t* err, void* data) {
  // Walking downward (API call first), so the last non-empty description is the innermost one.
  if (err->desc && *err->desc) *static_cast<std::string*>(data) = err->desc;
  return 0;
}

// Set when closing a file failed (a full disk at the final flush). HDF5 1.10 then keeps a
// half-torn-down file in its ID table and segfaults closing it again in its atexit handler
// (H5F__close_cb), so the library is terminated at exit only while no file close has failed.
std::atomic<bool> file_close_failed{false};

struct LibraryLifetime {
  LibraryLifetime() {
    // Not LibraryLock: its quiet_errors() would start the library, and H5dont_atexit must come
    // before anything else.
    const std::lock_guard<std::recursive_mutex> lock(library_mutex());
    if (H5dont_atexit() >= 0) {
      std::atexit([] {
        // A thread still inside HDF5 at exit (a detached one): skip the clean-up rather than
        // race it or wait for it.
        std::unique_lock<std::recursive_mutex> lock(library_mutex(), std::try_to_lock);
        if (lock.owns_lock() && !file_close_failed.load()) H5close();
      });
    }
  }
};
const LibraryLifetime library_lifetime;

}  // namespace

Handle& Handle::operator=(Handle&& o) noexcept {
  if (this != &o) {
    reset();
    id_ = o.id_;
    closer_ = o.closer_;
    o.id_ = -1;
  }
  return *this;
}

void Handle::reset() {
  if (id_ < 0) return;  // empty or moved from: nothing to close, no lock to take
  const LibraryLock lock;
  // A failed close here is already being handled (an exception unwinding): drop its error stack.
  if (!close()) H5Eclear2(H5E_DEFAULT);
}

bool Handle::close() {
  if (id_ < 0 || !closer_) {
    id_ = -1;
    return true;
  }
  const LibraryLock lock;
  const herr_t status = closer_(id_);
  if (status < 0 && closer_ == &H5Fclose) file_close_failed.store(true);
  id_ = -1;
  return status >= 0;
}

std::recursive_mutex& library_mutex() {
  static auto* const mutex = new std::recursive_mutex;  // never destroyed: see the header
  return *mutex;
}

LibraryLock::LibraryLock() : guard_(library_mutex()) {
  quiet_errors();
}

void quiet_errors() {
  // Per thread: a thread-safe HDF5 keeps the automatic error printing per thread, so a frame
  // writer or a sweep run's thread would otherwise print HDF5's error stack on every failure.
  thread_local bool quiet = false;
  if (quiet) return;
  const std::lock_guard<std::recursive_mutex> guard(library_mutex());
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  quiet = true;
}

std::string error_detail() {
  const LibraryLock lock;
  std::string detail;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD, innermost, &detail);
  H5Eclear2(H5E_DEFAULT);
  return detail.empty() ? std::string() : " (HDF5: " + detail + ")";
}

}  // namespace sinew::formats::hdf5
