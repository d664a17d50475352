#pragma once
// Pose files: a tool's recorded trajectory, one sample per row, in one of two
// text formats chosen by the file extension.
//
// CSV (.csv): a header line naming the nine columns (any order, each once,
// no others), then one row per sample:
//     time,x,y,z,qw,qx,qy,qz,closure
//     0,0.1,0.2,0.9,1,0,0,0,0.6
// JSON lines (.jsonl, .ndjson): one object per line with exactly these keys:
//     {"t": 0.0, "p": [0.1, 0.2, 0.9], "q": [1, 0, 0, 0], "closure": 0.6}
// Units: time in seconds, position in metres (world frame), quaternion
// w x y z (tool -> world), closure = jaw opening angle in radians in [0, pi].
// In both formats empty lines and lines starting with '#' are skipped.
// Checks: every value a finite number; | |q| - 1 | <= 1e-3 (then normalized);
// closure in [0, pi]; times strictly increasing; at least one sample.
// Bad input throws one sflsh::Error naming the file, the line and the field.
#include <string>
#include <vector>

#include "sflsh/teleop/pose_sample.hpp"

namespace sflsh::teleop {

enum class PoseFileFormat { kCsv, kJsonLines };

/// The format of `path` from its extension (.csv; .jsonl or .ndjson); throws
/// naming `path` and the accepted extensions otherwise.
PoseFileFormat pose_file_format(const std::string& path);

/// Reads a pose file (format from the extension). Throws sflsh::Error on a
/// missing file or bad content (see the file comment).
std::vector<PoseSample> read_pose_file(const std::string& path);

/// Parses pose-file text; `name` is used in error messages in place of a path.
std::vector<PoseSample> parse_pose_text(const std::string& text, PoseFileFormat format, const std::string& name);

/// The header line of `format` without newline ("" for JSON lines, which has none).
std::string pose_file_header(PoseFileFormat format);
/// One row of `format` for `s` without newline; numbers are written with 17
/// significant digits so that reading them back gives the same doubles.
std::string format_pose_row(const PoseSample& s, PoseFileFormat format);

/// Writes `samples` to `path` atomically (format from the extension).
void write_pose_file(const std::string& path, const std::vector<PoseSample>& samples);

}  // namespace sflsh::teleop
