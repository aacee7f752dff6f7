#pragma once
// A live session (docs/live.md): one engine, stepped in its own thread, steered between steps by
// commands from the server, streaming frames of the bound skin surface at display rate and, on
// request, recording through the results writer of sinew-simulate.
//
// The engine thread owns the backend. Each turn of its loop: apply the queued commands (through
// the Backend's steering calls, i.e. the BackendCore: never a new plan), write a recorded frame
// when one falls due, run a chunk of steps sized to ~chunk_seconds of wall time, and publish a
// frame when 1/frame_rate has passed and it stepped (or right after a command, so its effect is
// shown at once). Publishing copies the skin's displacement and hands the encoded frame to the
// sink; the sink (the server) must not block: a slow client drops frames, the engine never waits.
#include <array>
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "sinew/live/playback.hpp"
#include "sinew/live/protocol.hpp"
#include "sinew/live/steering_log.hpp"
#include "sinew/simulator/engine/state.hpp"
#include "sinew/simulator/output/output_schedule.hpp"
#include "sinew/simulator/run/run_setup.hpp"

namespace sinew::simulator {
class ResultsWriter;
}

namespace sinew::live {

// What a live run plans beyond the scene (BackendCore steering): activation overrides when it
// simulates muscles (its Δt then assumes activation 1) and one force slot for drags when it
// simulates loads. Pass to simulator::load_run.
void make_live_setup(simulator::Setup& setup);
// The same for playback (--play): the force slot only, so the replay runs the saved run's own plan
// (its Δt) and sliders go up to each curve's peak.
void make_playback_setup(simulator::Setup& setup);

struct SessionOptions {
  double frame_rate = 30;        // frames per second streamed (at most)
  double chunk_seconds = 0.004;  // wall time per chunk of steps (command latency)
  double max_speed = 0;          // simulated s per wall s at most (0: as fast as it goes)
  // Record from the start into this folder ("" none); this folder, or DIR-2, DIR-3, … when it
  // exists, for every recording (no folder is used twice).
  std::string record_dir;
  bool start_paused = false;
  bool pause_at_end = true;        // pause once when the scene's duration is reached
  std::string surface;             // visual surface to stream ("" the first visual one)
  double drag_radius_default = 0;  // m (0: 3 voxels)
  std::string play;                // a results file to scrub through first (playback.hpp)
  std::string up = "z";            // the model's up axis for the page's camera: "y" or "z"
};

// What the page needs to draw the model: the streamed surface at rest.
struct SurfaceView {
  std::string name;
  std::vector<float> rest;               // V × 3, m
  std::vector<std::uint32_t> triangles;  // T × 3
  std::vector<formats::Index> nodes;     // the nodes the surface's vertices depend on
  // Per vertex its 8 (index into nodes, trilinear weight) of its embedding element, and element.
  std::vector<std::array<std::pair<std::uint32_t, double>, 8>> weights;
  std::vector<formats::Index> element;
};

class Session {
 public:
  using Sink = std::function<void(std::shared_ptr<const std::string> message, bool binary)>;

  Session(simulator::LoadedRun run, SessionOptions options);
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  void start();  // starts the engine thread
  void stop();   // stops it (and finishes a recording)
  // Messages for every client (frames binary, status JSON); called from the engine thread.
  void set_sink(Sink sink);

  // Thread-safe. Checks what can be checked without the engine (muscle names) and queues the
  // command; throws ProtocolError for the client.
  void submit(const Command& c);

  // For a new client: the "hello" JSON and the mesh message, and the latest frame and status.
  std::string hello_json() const;
  std::shared_ptr<const std::string> mesh_message() const { return mesh_; }
  std::shared_ptr<const std::string> latest_frame() const;
  std::shared_ptr<const std::string> latest_status() const;

  // Test and bench hooks (thread-safe).
  std::int64_t step_index() const { return step_.load(); }
  // Steps the engine thread has run since start (resets and replays do not lower it), and the
  // wall time inside those step calls (s): the stepping speed without commands, frames or resets.
  std::int64_t steps_run() const { return steps_run_.load(); }
  double stepping_seconds() const { return 1e-9 * double(stepping_ns_.load()); }
  bool paused() const { return paused_.load(); }
  // Blocks until the engine thread has applied every command submitted so far (timeout s).
  bool wait_idle(double timeout_seconds);
  std::string last_error() const;
  // Why a drag would be refused ("" when dragging works): the scene lacks the effect 'loads', or
  // the backend has no force slots. Sent in "hello" for the page to say.
  std::string drag_refusal() const;

 private:
  void loop();
  // The engine stops where it is: paused, pending steps dropped, `message` shown as the error
  // (an instability, or any other failure of the engine or of a played-back file).
  void stop_with_error(const std::string& message);
  void apply(const Command& c);
  void publish_frame();
  // Frame from the displacements of surface_.nodes (3 per node, m) and, when field_ is an element
  // field, its value per model element (E values).
  void publish_surface(const std::vector<double>& sub, const std::vector<double>& element_values,
                       std::int64_t step, double time);
  void seek(std::size_t frame);
  void publish_status();
  // Keeps msg as the latest of its kind (for new clients) and hands it to the sink.
  void publish(std::shared_ptr<const std::string> msg, bool binary,
               std::shared_ptr<const std::string>& latest);
  void start_recording(const std::string& base);  // into a new folder (claim_recording_folder)
  void record_frame_if_due();
  void finish_recording();
  std::vector<formats::Index> nodes_near(const std::array<double, 3>& point, double radius);

  simulator::LoadedRun run_;
  SessionOptions options_;
  SurfaceView surface_;
  std::vector<std::string> muscle_names_;
  std::shared_ptr<const std::string> mesh_;
  simulator::State initial_;

  mutable std::mutex mutex_;  // guards queue_, sink_, latest_*, error_
  std::condition_variable wake_, idle_;
  std::vector<Command> queue_;
  std::uint64_t submitted_ = 0, applied_ = 0;
  Sink sink_;
  std::shared_ptr<const std::string> latest_frame_, latest_status_;
  std::string error_;  // the engine's last message (instability or another failure)

  std::thread thread_;
  std::atomic<bool> stop_{false}, paused_{false};
  std::atomic<std::int64_t> step_{0}, steps_run_{0}, stepping_ns_{0};
  // Engine-thread state.
  std::int64_t pending_steps_ = 0, chunk_ = 1;
  std::uint32_t last_id_ = 0;
  bool changed_ = false, at_end_ = false;
  Field field_ = Field::displacement;
  double steps_per_second_ = 0, sim_per_wall_ = 0;
  SteeringLog log_;
  bool dragging_ = false;
  // Recording.
  std::unique_ptr<simulator::ResultsWriter> writer_;
  std::string record_dir_;
  std::int64_t next_record_ = 0, last_recorded_ = -1;
  std::optional<simulator::OutputSchedule> schedule_;
  // Playback: frames from a results file until "continue" replays the scene to the shown frame.
  std::unique_ptr<RecordedRun> playback_;
  std::atomic<bool> playing_{false};
  std::size_t shown_frame_ = 0;
  std::string playback_hello_;  // the frames' times and steps for "hello" (fixed at start)
  // The fields the file can colour by, by Field (fixed at start; submit() reads it).
  std::array<bool, 3> playback_fields_{true, false, false};
};

}  // namespace sinew::live
