#pragma once
// Writes a run's frames (Backend::frame) through its ResultsWriter, in the order given, either at
// once on the caller's thread or on one background thread while the caller steps on.
//
// In the background the caller hands a frame over (its displacements and energies already on the
// host) and continues; the worker computes the deferred element fields (Frame::fields) and appends
// the frame to results.h5 (HDF5, surfaces, XDMF index). At most `depth` frames wait: a caller that
// gets ahead of the disk waits for the oldest, so memory stays bounded. Results are the same bits
// either way: the fields come from the frame's own copy of u(n) and activations.
//
// The ResultsWriter is touched only by the worker while frames are pending; finish() returns once
// every handed frame is in the file (before a checkpoint: the run's files are not used from two
// threads at once, and a checkpoint must never lie ahead of the frames on disk). HDF5 calls of
// other threads (other runs of a sweep) are serialised by formats' lock (hdf5_file.hpp). A worker's error (a full disk)
// is rethrown on the caller's thread by the next push() or finish(); frames after it are dropped.
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <exception>
#include <mutex>
#include <thread>

#include "sinew/simulator/engine/backend.hpp"
#include "sinew/simulator/output/results_writer.hpp"

namespace sinew::simulator {

class FrameWriter {
 public:
  // background: write on a worker thread (Backend::host_idle_while_stepping); else in push().
  // time_scaling: frame times are written as scene time, engine time / time_scaling.
  FrameWriter(ResultsWriter& results, bool background, double time_scaling, std::size_t depth = 2);
  // Joins the worker; frames still pending are written first, and errors are dropped (call
  // finish() to see them).
  ~FrameWriter();
  FrameWriter(const FrameWriter&) = delete;
  FrameWriter& operator=(const FrameWriter&) = delete;

  void push(Frame frame);
  // Waits until every frame handed over is written; rethrows the worker's first error.
  void finish();
  // Frames in results.h5 so far (read by the caller while the worker writes).
  std::int64_t frames_written() const;
  // Seconds spent writing frames: fields, HDF5 and index (on the worker when in the background,
  // overlapped with the steps).
  double write_seconds() const;

 private:
  void write(Frame& frame);
  void work();
  void rethrow_error();

  ResultsWriter& results_;
  const bool background_;
  const double time_scaling_;
  const std::size_t depth_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<Frame> queue_;
  bool busy_ = false, stop_ = false;
  std::exception_ptr error_;
  std::int64_t written_ = 0;
  double seconds_ = 0;
  std::thread worker_;
};

}  // namespace sinew::simulator
