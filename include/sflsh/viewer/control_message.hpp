#pragma once
// The browser viewer's control messages (page -> server): small JSON objects,
// one per WebSocket text message. Parsing is a pure function of the text, so
// it can be fuzzed and tested without a socket.
//
// Every message is a JSON object with a string "type" and an integer "seq"
// (0 <= seq < 2^53, increasing per client; the server echoes the last applied
// one in every frame so the page can time input to photon). Types and fields:
//   {"type":"tool",  "seq":n, "t":s, "tool":i, "pos":[x,y,z], "quat":[w,x,y,z], "closure":a}
//        device pose of tool i (default 0): t device time (s, increasing),
//        pos world (m), quat tool -> world (|q| within 1e-3 of 1), closure jaw
//        opening angle in [0, pi] rad (0 = shut). Checked further by the
//        server's stream filter (speed, time order: teleop/pose_stream_filter.hpp).
//   {"type":"pause", "seq":n, "paused":true|false}
//   {"type":"step",  "seq":n}                  one step (live) / one frame (playback), when paused
//   {"type":"reset", "seq":n}                  back to the start
//   {"type":"stiffness", "seq":n, "scale":k}   material stiffness scale, k in [0.1, 10]
//   {"type":"seek",  "seq":n, "time":s}        playback: go to time s (s >= 0)
//   {"type":"speed", "seq":n, "speed":v}       playback speed, v in [0.05, 8]
// Unknown fields are ignored; anything else (not JSON, not an object, an
// unknown type, a missing or mistyped field, a value out of range, more than
// kMaxControlMessageBytes) is rejected with a sentence naming the field.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "sflsh/teleop/pose_sample.hpp"

namespace sflsh::viewer {

constexpr std::size_t kMaxControlMessageBytes = 4096;
constexpr double kMinStiffnessScale = 0.1, kMaxStiffnessScale = 10.0;
constexpr double kMinPlaybackSpeed = 0.05, kMaxPlaybackSpeed = 8.0;

enum class ControlType { kTool, kPause, kStep, kReset, kStiffness, kSeek, kSpeed };

/// Short stable name ("tool", "pause", ...), as in the JSON "type".
const char* to_string(ControlType type);

struct ControlMessage {
  ControlType type = ControlType::kPause;
  std::uint64_t seq = 0;
  int client = 0;                ///< set by the server: the id of the sending client
  int tool = 0;                  ///< kTool: the scene's tool index
  teleop::PoseSample pose;       ///< kTool: the device pose (pose.time = "t")
  bool paused = false;           ///< kPause
  double value = 0;              ///< kStiffness: scale; kSeek: time (s); kSpeed: speed
};

/// The message, or why the text is not one (`error`: one sentence naming the field).
struct ControlParse {
  std::optional<ControlMessage> message;
  std::string error;
};

/// Parses one control message (see the file comment). Never throws.
ControlParse parse_control_message(std::string_view text);

}  // namespace sflsh::viewer
