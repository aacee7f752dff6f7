// Host side of the CUDA backend's entry point (logging lives here: spdlog/fmt stay out of .cu
// files); the engine itself is in cuda_backend.cu, or absent when built without CUDA.
#include "sinew/simulator/cuda_backend.hpp"

#include "sinew/common/error.hpp"
#include "sinew/common/log.hpp"

namespace sinew::simulator {

#if defined(SINEW_CUDA_ENABLED)
namespace detail {
std::unique_ptr<Backend> make_cuda_engine(const formats::Model& model, const Setup& setup,
                                          Plan plan, const CudaOptions& options);
}  // namespace detail

std::unique_ptr<Backend> make_cuda_backend(const formats::Model& model, const Setup& setup,
                                           const CudaOptions& options) {
  if (!cuda_device_available())
    throw ConfigError("", "device",
                      "the CUDA backend was requested but no CUDA device is available");
  Plan plan = make_plan(model, setup);
  for (const auto& w : plan.warnings) log::warn("{}", w);
  return detail::make_cuda_engine(model, setup, std::move(plan), options);
}
#else
bool cuda_device_available() {
  return false;
}
std::string cuda_device_name() {
  return "";
}

std::unique_ptr<Backend> make_cuda_backend(const formats::Model&, const Setup&,
                                           const CudaOptions&) {
  throw ConfigError("", "device",
                    "the CUDA backend was requested but sinew was built without CUDA "
                    "(configure with -DSINEW_WITH_CUDA=ON where nvcc is available)");
}

double measure_copy_bandwidth(std::size_t, int) {
  throw ConfigError("", "device", "sinew was built without CUDA");
}
#endif

}  // namespace sinew::simulator
