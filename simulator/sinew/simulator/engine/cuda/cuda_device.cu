// The CUDA backend's entry points: device queries, the engine factory (make_cuda_backend in
// cuda_backend.cpp checks the options and logs), and the copy-bandwidth probe of the benchmarks.
#include <cuda_runtime.h>

#include <algorithm>
#include <vector>

#include "sinew/simulator/engine/cuda/cuda_engine.cuh"
#include "sinew/simulator/engine/cuda/device_array.cuh"
#include "sinew/simulator/engine/cuda_backend.hpp"

namespace sinew::simulator {

int cuda_device_count() {
  int count = 0;
  if (cudaGetDeviceCount(&count) != cudaSuccess) {
    cudaGetLastError();
    return 0;
  }
  return count;
}

bool cuda_device_available() {
  return cuda_device_count() > 0;
}

void set_cuda_blocking_wait(int device, bool blocking) {
  // On a device already in use the primary context's flags are replaced (CUDA 11 and later).
  SINEW_CUDA_CHECK(cudaSetDevice(device));
  unsigned flags = 0;
  SINEW_CUDA_CHECK(cudaGetDeviceFlags(&flags));
  // The other flags kept, but cudaDeviceMapHost, which the getter may report and the setter does
  // not take (it is implicit).
  flags = (flags & ~unsigned(cudaDeviceScheduleMask | cudaDeviceMapHost)) |
          (blocking ? cudaDeviceScheduleBlockingSync : cudaDeviceScheduleAuto);
  SINEW_CUDA_CHECK(cudaSetDeviceFlags(flags));
}

namespace detail {
bool cuda_device_properties(CudaDeviceProperties& out) {
  if (!cuda_device_available()) return false;
  cudaDeviceProp p{};
  SINEW_CUDA_CHECK(cudaGetDeviceProperties(&p, 0));
  out = {p.name, p.major, p.minor, p.multiProcessorCount, double(p.totalGlobalMem)};
  return true;
}
}  // namespace detail

namespace detail {
std::unique_ptr<Backend> make_cuda_engine(const formats::Model& model, const Setup& setup,
                                          Plan plan, const CudaOptions& options) {
  if (setup.precision == Precision::float32)
    return std::make_unique<cuda::CudaEngine<float>>(model, setup, std::move(plan), options);
  return std::make_unique<cuda::CudaEngine<double>>(model, setup, std::move(plan), options);
}
}  // namespace detail

double measure_copy_bandwidth(std::size_t bytes, int repeats) {
  cuda::DeviceArray<char> a, b;
  a.allocate(bytes);
  b.allocate(bytes);
  SINEW_CUDA_CHECK(cudaMemset(a.get(), 1, bytes));
  cudaEvent_t e0, e1;
  SINEW_CUDA_CHECK(cudaEventCreate(&e0));
  SINEW_CUDA_CHECK(cudaEventCreate(&e1));
  std::vector<float> ms;
  for (int k = 0; k < repeats + 3; ++k) {
    SINEW_CUDA_CHECK(cudaEventRecord(e0));
    SINEW_CUDA_CHECK(cudaMemcpy(b.get(), a.get(), bytes, cudaMemcpyDeviceToDevice));
    SINEW_CUDA_CHECK(cudaEventRecord(e1));
    SINEW_CUDA_CHECK(cudaEventSynchronize(e1));
    float t = 0;
    SINEW_CUDA_CHECK(cudaEventElapsedTime(&t, e0, e1));
    if (k >= 3) ms.push_back(t);
  }
  cudaEventDestroy(e0);
  cudaEventDestroy(e1);
  std::sort(ms.begin(), ms.end());
  return 2.0 * double(bytes) / (double(ms[ms.size() / 2]) * 1e-3);
}

}  // namespace sinew::simulator
