#pragma once
// CUDA runtime checks of the CUDA engine: a failed call throws sinew::Error naming the call and
// where it was made (the GPU's own findings travel in a StepStatus, read at sync points).
#include <cuda_runtime.h>

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
