#pragma once
// Device and pinned host arrays of the CUDA engine (RAII over CUDA's stream-ordered allocator, or
// cudaMalloc where a device has none, and cudaMallocHost).
#include <cuda_runtime.h>

#include <cstddef>
#include <utility>
#include <vector>

#include "sinew/simulator/engine/cuda/cuda_check.cuh"

namespace sinew::simulator::cuda {

// Whether the current device has CUDA's stream-ordered allocator (cudaMallocAsync, cudaFreeAsync:
// CUDA 11.2 and later, most devices). cudaFree waits for the whole device, that is for the graphs
// every engine of the process has queued; cudaFreeAsync waits for nothing.
inline bool stream_ordered_allocator() {
  static const bool yes = [] {
    int device = 0, supported = 0;
    if (cudaGetDevice(&device) != cudaSuccess ||
        cudaDeviceGetAttribute(&supported, cudaDevAttrMemoryPoolsSupported, device) !=
            cudaSuccess) {
      cudaGetLastError();
      return false;
    }
    return supported != 0;
  }();
  return yes;
}

template <typename V>
class DeviceArray {
 public:
  DeviceArray() = default;
  DeviceArray(const DeviceArray&) = delete;
  DeviceArray& operator=(const DeviceArray&) = delete;
  DeviceArray(DeviceArray&& o) noexcept : p_(o.p_), n_(o.n_) {
    o.p_ = nullptr;
    o.n_ = 0;
  }
  DeviceArray& operator=(DeviceArray&& o) noexcept {
    std::swap(p_, o.p_);
    std::swap(n_, o.n_);
    return *this;
  }
  // Freed on the legacy stream, which orders itself after none of the engines' non-blocking
  // streams: whoever frees or reallocates makes sure no queued work still uses the array (the
  // engine synchronises its streams first).
  ~DeviceArray() {
    if (p_) stream_ordered_allocator() ? cudaFreeAsync(p_, cudaStreamLegacy) : cudaFree(p_);
  }
  void allocate(std::size_t n) {
    if (p_)
      SINEW_CUDA_CHECK(stream_ordered_allocator() ? cudaFreeAsync(p_, cudaStreamLegacy)
                                                  : cudaFree(p_));
    p_ = nullptr;
    n_ = n;
    if (!n) return;
    if (!stream_ordered_allocator()) {
      SINEW_CUDA_CHECK(cudaMalloc(&p_, n * sizeof(V)));
      return;
    }
    SINEW_CUDA_CHECK(cudaMallocAsync(&p_, n * sizeof(V), cudaStreamLegacy));
    // Usable on every stream from here (the legacy stream holds nothing else of the engines').
    SINEW_CUDA_CHECK(cudaStreamSynchronize(cudaStreamLegacy));
  }
  // Transfers in the order of `stream` (the engine's step stream), completed before returning.
  // Only that stream is waited for: a device-wide synchronisation would also wait for the graphs
  // that engines of other host threads (sinew-sweep --concurrent) have queued, and stall their
  // queues meanwhile.
  void upload(const std::vector<V>& v, cudaStream_t stream) {
    allocate(v.size());
    if (n_)
      SINEW_CUDA_CHECK(
          cudaMemcpyAsync(p_, v.data(), n_ * sizeof(V), cudaMemcpyHostToDevice, stream));
    SINEW_CUDA_CHECK(cudaStreamSynchronize(stream));
  }
  void zero(cudaStream_t stream) {
    if (n_) SINEW_CUDA_CHECK(cudaMemsetAsync(p_, 0, n_ * sizeof(V), stream));
    SINEW_CUDA_CHECK(cudaStreamSynchronize(stream));
  }
  std::vector<V> download(cudaStream_t stream) const {
    std::vector<V> v(n_);
    if (n_)
      SINEW_CUDA_CHECK(
          cudaMemcpyAsync(v.data(), p_, n_ * sizeof(V), cudaMemcpyDeviceToHost, stream));
    SINEW_CUDA_CHECK(cudaStreamSynchronize(stream));
    return v;
  }
  V* get() const { return p_; }
  std::size_t size() const { return n_; }
  std::size_t bytes() const { return n_ * sizeof(V); }

 private:
  V* p_ = nullptr;
  std::size_t n_ = 0;
};

template <typename V>
class PinnedArray {
 public:
  PinnedArray() = default;
  PinnedArray(const PinnedArray&) = delete;
  PinnedArray& operator=(const PinnedArray&) = delete;
  ~PinnedArray() {
    if (p_) cudaFreeHost(p_);
  }
  void allocate(std::size_t n) {
    if (p_) SINEW_CUDA_CHECK(cudaFreeHost(p_));
    p_ = nullptr;
    n_ = n;
    if (n) SINEW_CUDA_CHECK(cudaMallocHost(&p_, n * sizeof(V)));
  }
  V* get() const { return p_; }
  std::size_t size() const { return n_; }

 private:
  V* p_ = nullptr;
  std::size_t n_ = 0;
};

}  // namespace sinew::simulator::cuda
