#include "sinew/simulator/output/frame_writer.hpp"

#include <chrono>
#include <utility>

namespace sinew::simulator {

FrameWriter::FrameWriter(ResultsWriter& results, bool background, double time_scaling,
                         std::size_t depth)
    : results_(results),
      background_(background),
      time_scaling_(time_scaling),
      depth_(depth < 1 ? 1 : depth),
      written_(results.frame_count()) {
  if (background_) worker_ = std::thread([this] { work(); });
}

FrameWriter::~FrameWriter() {
  if (!background_) return;
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  worker_.join();
}

void FrameWriter::write(Frame& frame) {
  const auto t0 = std::chrono::steady_clock::now();
  const ElementFields fields = frame.fields ? frame.fields() : ElementFields{};
  results_.append_frame(frame.time / time_scaling_, frame.step, frame.displacements, fields);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::lock_guard lock(mutex_);
  ++written_;
  seconds_ += s;
}

void FrameWriter::push(Frame frame) {
  if (!background_) {
    write(frame);
    return;
  }
  std::unique_lock lock(mutex_);
  // Bounded: wait for the oldest frame when `depth_` are pending (or stop at an error).
  changed_.wait(lock, [&] { return error_ || queue_.size() + (busy_ ? 1 : 0) < depth_; });
  if (error_) std::rethrow_exception(error_);
  queue_.push_back(std::move(frame));
  lock.unlock();
  changed_.notify_all();
}

void FrameWriter::finish() {
  if (!background_) return;
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [&] { return error_ || (queue_.empty() && !busy_); });
  if (error_) std::rethrow_exception(error_);
}

std::int64_t FrameWriter::frames_written() const {
  std::lock_guard lock(mutex_);
  return written_;
}

double FrameWriter::write_seconds() const {
  std::lock_guard lock(mutex_);
  return seconds_;
}

void FrameWriter::work() {
  std::unique_lock lock(mutex_);
  for (;;) {
    changed_.wait(lock, [&] { return stop_ || !queue_.empty(); });
    // After an error nothing more is written: the file ends at the last good frame.
    if (queue_.empty() || error_) {
      if (stop_) return;
      queue_.clear();
      continue;
    }
    Frame frame = std::move(queue_.front());
    queue_.pop_front();
    busy_ = true;
    lock.unlock();
    std::exception_ptr error;
    try {
      write(frame);
    } catch (...) {
      error = std::current_exception();
    }
    lock.lock();
    busy_ = false;
    if (error && !error_) error_ = error;
    changed_.notify_all();
  }
}

}  // namespace sinew::simulator
