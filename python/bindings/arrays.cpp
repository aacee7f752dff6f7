// Arrays handed to sinew from Python: checked before anything reaches an engine, so a NaN or a
// wrong shape is a ConfigError naming the argument, never a crash or a poisoned state.
#include <fmt/format.h>

#include <cmath>

#include "bindings.hpp"
#include "sinew/common/error.hpp"

namespace sinew::python {

std::vector<double> finite_doubles(const py::handle& values, const std::string& what,
                                   py::ssize_t cols) {
  py::array_t<double, py::array::c_style | py::array::forcecast> a;
  try {
    a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(values);
  } catch (const py::error_already_set&) {
    a = {};
  }
  if (!a) throw ConfigError("", what, "expected an array of numbers");
  const bool shape_ok = cols == 0 ? a.ndim() == 1 : (a.ndim() == 2 && a.shape(1) == cols);
  if (!shape_ok) {
    std::string got;
    for (py::ssize_t d = 0; d < a.ndim(); ++d) got += (d ? " × " : "") + std::to_string(a.shape(d));
    throw ConfigError(
        "", what,
        fmt::format("expected shape {}, got ({})", cols == 0 ? "(n)" : fmt::format("(n, {})", cols),
                    a.ndim() == 0 ? "a scalar" : got));
  }
  std::vector<double> out(a.data(), a.data() + a.size());
  for (std::size_t i = 0; i < out.size(); ++i) {
    if (!std::isfinite(out[i])) {
      throw ConfigError("", what, fmt::format("value {} is not finite", out[i]))
          .at(static_cast<std::int64_t>(cols == 0 ? i : i / static_cast<std::size_t>(cols)));
    }
  }
  return out;
}

std::vector<std::int32_t> node_ids(const py::handle& values, const std::string& what,
                                   std::size_t count) {
  const py::array raw = py::array::ensure(values);
  if (!raw || raw.ndim() != 1)
    throw ConfigError("", what, "expected a one-dimensional list of node ids");
  if (raw.size() > 0 && raw.dtype().kind() != 'i' && raw.dtype().kind() != 'u')
    throw ConfigError("", what,
                      "node ids must be integers, got dtype " + std::string(py::str(raw.dtype())));
  const auto ids =
      py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>::ensure(raw);
  std::vector<std::int32_t> out;
  out.reserve(static_cast<std::size_t>(ids.size()));
  for (py::ssize_t i = 0; i < ids.size(); ++i) {
    const std::int64_t id = ids.data()[i];
    if (id < 0 || static_cast<std::uint64_t>(id) >= count)
      throw ConfigError("", what, fmt::format("node id {} out of range [0, {})", id, count)).at(i);
    out.push_back(static_cast<std::int32_t>(id));
  }
  return out;
}

}  // namespace sinew::python
