#pragma once
// CUDA runtime checks of the CUDA engine: a failed call throws sinew::Error naming the call and
// where it was made (the GPU's own findings travel in a StepStatus, read at sync points).
#include <cuda_runtime.h>

#include <mutex>
#include <string>

#include "sinew/common/error.hpp"

#define SINEW_CUDA_CHECK(call)                                                                    \
  do {                                                                                            \
    const cudaError_t sinew_cuda_status_ = (call);                                                \
    if (sinew_cuda_status_ != cudaSuccess)                                                        \
      throw ::sinew::Error(std::string(__FILE__) + ":" + std::to_string(__LINE__), #call,         \
                           std::string("CUDA error: ") + cudaGetErrorString(sinew_cuda_status_)); \
  } while (0)
#define SINEW_CUDA_LAUNCHED() SINEW_CUDA_CHECK(cudaGetLastError())

namespace sinew::simulator::cuda {

// Engines in several host threads (sinew-sweep --concurrent, sinew-live beside a batch run) share
// the device. None of them synchronises the whole device (cudaDeviceSynchronize): that would wait
// for every other engine's queued graphs, stall their queues meanwhile, and invalidate a capture
// in progress. Each engine waits for its own streams only (DeviceArray's transfers take the
// stream). Graph captures take this lock, so that they stay one at a time.
inline std::mutex& capture_mutex() {
  static std::mutex m;
  return m;
}

}  // namespace sinew::simulator::cuda
