#pragma once
// Records what a live session's simulator used from the pose stream, as a
// pose file (pose_file.hpp) that replays the session offline.
//
// One row per record() call with time = the sample's receive_time (the clock
// the caller passed to PoseStreamServer::poll, e.g. simulation time) and the
// accepted, normalized pose. Record the sample poll() returns (the newest one
// of each poll, the one the simulation uses); then an offline run that reads
// the file into a PoseTrack and samples it with PoseInterpolation::kHold at
// the same step times feeds the simulator bit-identical poses. Numbers are
// written with 17 significant digits, so the doubles read back are identical.
//
// The file is written as PATH.partial and renamed to PATH by finish(); a
// recorder destroyed without finish() leaves nothing behind.
#include <fstream>
#include <memory>
#include <string>

#include "sflsh/io/atomic_output.hpp"
#include "sflsh/teleop/pose_file.hpp"
#include "sflsh/teleop/pose_stream_server.hpp"

namespace sflsh::teleop {

class PoseRecorder {
 public:
  /// Starts the file `path` (.csv or .jsonl/.ndjson: the format is taken from
  /// the extension); throws when it cannot be written.
  explicit PoseRecorder(const std::string& path);

  /// Appends `s` with time = s.receive_time, which must be after the previous
  /// recorded one (throws otherwise: record once per poll, not every sample).
  void record(const StreamSample& s);

  /// Flushes and renames the file into place. Further record() calls throw.
  void finish();

  long rows() const { return rows_; }
  const std::string& path() const { return out_->path(); }

 private:
  std::unique_ptr<io::AtomicOutput> out_;
  std::ofstream file_;
  PoseFileFormat format_;
  long rows_ = 0;
  double last_time_ = 0.0;
  bool finished_ = false;
};

}  // namespace sflsh::teleop
