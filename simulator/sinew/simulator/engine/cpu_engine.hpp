#pragma once
// The CPU backend (OpenMP): the Backend of backend.hpp stepped on the host, every pass of
// passes/ run by cpu_for_each over the shared core (backend_core.hpp). Bit-identical for any
// thread count (backend.hpp, step 2).
#include <memory>

#include "sinew/formats/model.hpp"
#include "sinew/simulator/engine/backend.hpp"
#include "sinew/simulator/engine/setup.hpp"

namespace sinew::simulator {

// The CPU backend for the Setup's precision. Throws ConfigError on a bad Setup (see make_plan).
std::unique_ptr<Backend> make_cpu_backend(const formats::Model& model, const Setup& setup);

}  // namespace sinew::simulator
