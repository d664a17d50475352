#include "sflsh/teleop/pose_recorder.hpp"

#include "sflsh/core/error.hpp"

namespace sflsh::teleop {

PoseRecorder::PoseRecorder(const std::string& path) : format_(pose_file_format(path)) {
  out_ = std::make_unique<io::AtomicOutput>(path);
  file_.open(out_->temp_path(), std::ios::binary);
  require(file_.good(), out_->temp_path(), ": cannot write the pose recording");
  const std::string header = pose_file_header(format_);
  if (!header.empty()) file_ << header << '\n';
}

void PoseRecorder::record(const StreamSample& s) {
  require(!finished_, path(), ": record() after finish()");
  require(rows_ == 0 || s.receive_time > last_time_, path(), ": receive time ", s.receive_time,
          " s is not after the previous recorded ", last_time_, " s (record the newest sample of each poll)");
  PoseSample row = s.sample;
  row.time = s.receive_time;
  file_ << format_pose_row(row, format_) << '\n';
  last_time_ = s.receive_time;
  ++rows_;
}

void PoseRecorder::finish() {
  require(!finished_, path(), ": finish() called twice");
  file_.close();
  require(!file_.fail(), out_->temp_path(), ": write failed");
  out_->commit();
  finished_ = true;
}

}  // namespace sflsh::teleop
