#pragma once
// Typed exceptions for the host side. Every error names where it happened: a file, a field (an
// HDF5 dataset, a config key), an index when one applies, and the problem in plain words.
//
//   throw FormatError(path, "/elements/nodes", "node id 1234 out of range [0, 1000)").at(17);
//   -> "model.h5: /elements/nodes[17]: node id 1234 out of range [0, 1000)"
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>

namespace sinew {

class Error : public std::runtime_error {
 public:
  // file: a path or "" when none; field: a dataset, key or stage name, or "".
  Error(std::string file, std::string field, std::string problem);

  const std::string& file() const { return file_; }
  const std::string& field() const { return field_; }
  const std::string& problem() const { return problem_; }
  std::optional<std::int64_t> index() const { return index_; }

  const char* what() const noexcept override { return message_.c_str(); }

 protected:
  void set_index(std::int64_t index);

 private:
  void compose();
  std::string file_, field_, problem_, message_;
  std::optional<std::int64_t> index_;
};

// Chaining helper so every subclass keeps its own type: FormatError(...).at(i).
template <typename Derived>
class ErrorWithIndex : public Error {
 public:
  using Error::Error;
  Derived& at(std::int64_t index) & {
    set_index(index);
    return static_cast<Derived&>(*this);
  }
  Derived&& at(std::int64_t index) && {
    set_index(index);
    return static_cast<Derived&&>(*this);
  }
};

// A file (model, results) whose contents break the format.
class FormatError : public ErrorWithIndex<FormatError> {
 public:
  using ErrorWithIndex::ErrorWithIndex;
};
// A file that cannot be opened, read or written at the system level.
class IoError : public ErrorWithIndex<IoError> {
 public:
  using ErrorWithIndex::ErrorWithIndex;
};
// A spec or scene (YAML) with an unknown key, a wrong type or a value out of range.
class ConfigError : public ErrorWithIndex<ConfigError> {
 public:
  using ErrorWithIndex::ErrorWithIndex;
};
// Input geometry that cannot make a model (empty mesh, skull outside skin, ...).
class GeometryError : public ErrorWithIndex<GeometryError> {
 public:
  using ErrorWithIndex::ErrorWithIndex;
};
// A simulation that became unstable: NaN/Inf, inverted element, energy blow-up.
class InstabilityError : public ErrorWithIndex<InstabilityError> {
 public:
  using ErrorWithIndex::ErrorWithIndex;
};
// A request the machine cannot satisfy (memory estimate too large, no GPU, ...).
class ResourceError : public ErrorWithIndex<ResourceError> {
 public:
  using ErrorWithIndex::ErrorWithIndex;
};

}  // namespace sinew
