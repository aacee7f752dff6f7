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
  // Setup-time transfers on the legacy stream, completed before returning (the engine's work runs
  // on a non-blocking stream that does not order itself after the legacy stream).
  void upload(const std::vector<V>& v) {
    allocate(v.size());
    if (n_) SINEW_CUDA_CHECK(cudaMemcpy(p_, v.data(), n_ * sizeof(V), cudaMemcpyHostToDevice));
    device_synchronize();
  }
  void zero() {
    if (n_) SINEW_CUDA_CHECK(cudaMemset(p_, 0, n_ * sizeof(V)));
    device_synchronize();
  }
  std::vector<V> download() const {
    device_synchronize();
    std::vector<V> v(n_);
    if (n_) SINEW_CUDA_CHECK(cudaMemcpy(v.data(), p_, n_ * sizeof(V), cudaMemcpyDeviceToHost));
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
