#include "sinew/common/error.hpp"

#include <utility>

namespace sinew {

Error::Error(std::string file, std::string field, std::string problem)
    : std::runtime_error(problem),
      file_(std::move(file)),
      field_(std::move(field)),
      problem_(std::move(problem)) {
  compose();
}

void Error::set_index(std::int64_t index) {
  index_ = index;
  compose();
}

void Error::compose() {
  // Built with append: chained operator+ on temporaries trips a GCC 12 -Wrestrict false positive.
  message_.clear();
  if (!file_.empty()) message_.append(file_).append(": ");
  if (!field_.empty()) {
    message_.append(field_);
    if (index_) message_.append("[").append(std::to_string(*index_)).append("]");
    message_.append(": ");
  } else if (index_) {
    message_.append("[").append(std::to_string(*index_)).append("]: ");
  }
  message_.append(problem_);
}

}  // namespace sinew
