// `sflsh stream-listen`: the teleoperation stream on its own (no scene): listens
// on a loopback UDP port, checks every pose datagram (one stderr line per
// rejected one), answers at a fixed loop rate with a feedback message and
// optionally records the session as a pose file. For testing a device bridge
// and measuring the stream's latency with scripts/replay_pose_stream.py.
#include <chrono>
#include <cstdio>
#include <memory>
#include <thread>

#include "command.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/interrupt.hpp"
#include "sflsh/io/atomic_output.hpp"
#include "sflsh/teleop/pose_recorder.hpp"
#include "sflsh/teleop/pose_stream_server.hpp"

namespace sflsh::cli {
namespace {

struct StreamArgs {
  int port = 0;
  double rate = 1000.0, seconds = 0.0, max_speed = 20.0, spring = 0.0;
  std::string record;
};

void run_stream_listen(const StreamArgs& a) {
  require(a.port >= 0 && a.port <= 65535, "--port ", a.port, ": expected 0 (pick a free one) or 1..65535");
  require(a.rate > 0.0 && a.rate <= 1e5, "--rate ", a.rate, ": expected a loop rate in (0, 1e5] Hz");
  require(a.seconds >= 0.0, "--seconds ", a.seconds, ": expected >= 0 (0 = until Ctrl-C)");
  require(a.max_speed > 0.0, "--max-speed ", a.max_speed, ": expected > 0 m/s");
  require(a.spring >= 0.0, "--spring ", a.spring, ": expected >= 0 N/m");
  if (!a.record.empty()) {
    io::check_output_file(a.record, "--record");
    teleop::pose_file_format(a.record);
  }
  teleop::PoseStreamServerOptions o;
  o.port = a.port;
  o.checks.max_speed = a.max_speed;
  teleop::PoseStreamServer server(o);
  std::unique_ptr<teleop::PoseRecorder> recorder;
  if (!a.record.empty()) recorder = std::make_unique<teleop::PoseRecorder>(a.record);
  std::printf("listening on 127.0.0.1:%d (loop %g Hz", server.port(), a.rate);
  if (a.seconds > 0) std::printf(", %g s", a.seconds);
  std::printf("); Ctrl-C stops\n");
  std::fflush(stdout);

  // A fixed-rate loop on the wall clock: tick k at k / rate; `t` is the loop's
  // clock (s), used as receive time, so a recording replays with kHold at the
  // same tick times.
  InterruptScope interrupt_scope;
  const auto start = std::chrono::steady_clock::now();
  const auto period = std::chrono::duration<double>(1.0 / a.rate);
  std::optional<Vec3> rest;  // the spring's anchor: the first accepted position
  long ticks = 0, late_ticks = 0;
  for (;; ++ticks) {
    const double t = ticks / a.rate;
    if ((a.seconds > 0 && t >= a.seconds) || interrupt_signal() != 0) break;
    if (const auto s = server.poll(t)) {
      if (recorder) recorder->record(*s);
      if (!rest) rest = s->sample.position;
    }
    if (server.last_good())
      server.send_feedback(-a.spring * (server.last_good()->sample.position - *rest), Vec3::Zero(), t);
    const auto due = start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(period * (ticks + 1));
    if (std::chrono::steady_clock::now() > due) ++late_ticks;
    std::this_thread::sleep_until(due);
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  // Ctrl-C ends a live session normally: the recording is kept.
  if (recorder) recorder->finish();
  std::printf("%ld ticks in %.3f s (%ld late), %s, %ld feedback sent\n", ticks, wall, late_ticks,
              server.counters().describe().c_str(), server.feedback_sent());
  if (recorder) std::printf("recorded %ld samples to %s\n", recorder->rows(), recorder->path().c_str());
}

const CommandRegistrar reg(70, [](CLI::App& app) {
  auto a = std::make_shared<StreamArgs>();
  auto* cmd = app.add_subcommand(
      "stream-listen",
      "Teleoperation stream test bench (no scene): check device poses on a loopback UDP port, answer with feedback, "
      "record (README: Teleoperation stream)");
  cmd->add_option("--port", a->port, "UDP port on 127.0.0.1 (0 = pick a free one and print it)")->capture_default_str();
  cmd->add_option("--rate", a->rate, "Loop rate in Hz: poll and feedback once per tick")->capture_default_str();
  cmd->add_option("--seconds", a->seconds, "Run time in seconds (0 = until Ctrl-C)")->capture_default_str();
  cmd->add_option("--max-speed", a->max_speed, "Fastest believable tool motion in m/s (faster = a jump, rejected)")
      ->capture_default_str();
  cmd->add_option("--spring", a->spring,
                  "Feedback force stiffness in N/m toward the first received position (0 = zero force); "
                  "a stand-in load, not a simulation")
      ->capture_default_str();
  cmd->add_option("--record", a->record, "Record the accepted poses, stamped with the loop clock (.csv or .jsonl)");
  cmd->callback([a] { run_stream_listen(*a); });
});

}  // namespace
}  // namespace sflsh::cli
