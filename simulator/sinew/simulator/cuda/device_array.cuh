#pragma once
// Device and pinned host arrays of the CUDA engine (RAII over cudaMalloc / cudaMallocHost).
#include <cuda_runtime.h>

#include <cstddef>
#include <utility>
#include <vector>

#include "sinew/simulator/cuda/cuda_check.cuh"

namespace sinew::simulator::cuda {

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
  ~DeviceArray() {
    if (p_) cudaFree(p_);
  }
  void allocate(std::size_t n) {
    if (p_) SINEW_CUDA_CHECK(cudaFree(p_));
    p_ = nullptr;
    n_ = n;
    if (n) SINEW_CUDA_CHECK(cudaMalloc(&p_, n * sizeof(V)));
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
