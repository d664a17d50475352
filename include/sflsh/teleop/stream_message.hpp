#pragma once
// The teleoperation stream's wire format: UDP datagrams on the loopback
// interface, binary, little-endian, fixed size, no padding. One datagram is one
// message. All floating-point fields are IEEE-754 float64.
//
// Device -> simulator, "pose" message, 88 bytes (Python struct "<IHHQd3d4dd"):
//   offset  size  field
//        0     4  magic     uint32  0x50544653 (the bytes "SFTP")
//        4     2  version   uint16  2 (1 is accepted too: the pose layout is the same)
//        6     2  type      uint16  1 = pose
//        8     8  sequence  uint64  strictly increasing per device (gaps allowed)
//       16     8  time      float64 device timestamp, seconds, strictly increasing
//       24    24  position  3 x float64  x y z, metres, world frame
//       48    32  rotation  4 x float64  qw qx qy qz, unit quaternion (tool -> world)
//       80     8  closure   float64 jaw opening angle, radians, in [0, pi] (0 = shut)
//
// Simulator -> device, "feedback" message, 80 bytes (Python struct "<IHHQd3d3dII"),
// sent to the address the last accepted pose came from, once per accepted pose:
//        0     4  magic     uint32  0x50544653
//        4     2  version   uint16  2
//        6     2  type      uint16  2 = feedback
//        8     8  sequence  uint64  the sequence number of the newest accepted pose (echoed)
//       16     8  sim_time  float64 simulation time, seconds
//       24    24  force     3 x float64  force on the tool, newtons, world frame
//       48    24  torque    3 x float64  torque on the tool about its frame origin, N·m, world frame
//       72     4  status    uint32  0 = running, 1 = ramping in (the force is being faded in
//                                   after the first pose), 2 = ended (the simulation stopped:
//                                   force and torque are zero, sim_time is the final time)
//       76     4  reserved  uint32  0
// A device must render zero force unless the status is 0 or 1. Version 1's
// feedback (72 bytes, no status) is no longer sent.
//
// Anything else (another size, magic, version or type) is rejected by the
// receiver with a log line; see PoseStreamServer for the semantic checks.
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include "sflsh/core/types.hpp"
#include "sflsh/teleop/pose_sample.hpp"

namespace sflsh::teleop {

constexpr std::uint32_t kStreamMagic = 0x50544653u;  ///< "SFTP" read as a little-endian uint32
constexpr std::uint16_t kStreamVersion = 2;
constexpr std::uint16_t kOldestPoseVersion = 1;  ///< pose messages of versions 1..2 are read (same layout)
constexpr std::uint16_t kPoseMessageType = 1;
constexpr std::uint16_t kFeedbackMessageType = 2;
constexpr std::size_t kPoseMessageSize = 88;      ///< bytes
constexpr std::size_t kFeedbackMessageSize = 80;  ///< bytes

/// Device -> simulator.
struct PoseMessage {
  std::uint64_t sequence = 0;
  PoseSample sample;  ///< sample.time is the device timestamp
};

/// What the simulator is doing with the tool (feedback's status field).
enum class FeedbackStatus : std::uint32_t {
  kRunning = 0,  ///< the force is the simulation's
  kRampIn = 1,   ///< the tool is being brought to the device's pose; the force fades in
  kEnded = 2,    ///< the simulation stopped: zero force and torque, frozen sim_time
};
constexpr std::uint32_t kNumFeedbackStatus = 3;

/// Simulator -> device.
struct FeedbackMessage {
  std::uint64_t sequence = 0;  ///< echoed sequence number of the newest accepted pose
  double sim_time = 0.0;       ///< seconds
  Vec3 force = Vec3::Zero();   ///< N, world frame
  Vec3 torque = Vec3::Zero();  ///< N·m, world frame
  FeedbackStatus status = FeedbackStatus::kRunning;
};

/// Why a datagram was not used. The first four are decode failures; the rest
/// are the stream checks of PoseStreamFilter.
enum class RejectReason {
  kMalformed,          ///< wrong size for its type, or shorter than the 8-byte header
  kBadMagic,           ///< first 4 bytes are not kStreamMagic (garbage, another protocol)
  kBadVersion,         ///< a protocol version this build does not speak
  kWrongType,          ///< a message type the receiver does not expect
  kNonFinite,          ///< NaN or inf in time, position, rotation or closure
  kBadQuaternion,      ///< |q| differs from 1 by more than the tolerance
  kBadClosure,         ///< closure outside [0, pi]
  kTimeNotIncreasing,  ///< device time not after the last accepted sample's
  kJump,               ///< position moved faster than the maximum speed
  kOutOfOrder,         ///< sequence number not after the last accepted one
};
constexpr int kNumRejectReasons = 10;

/// Short stable name of a reason ("malformed", "bad magic", ...).
const char* to_string(RejectReason reason);

/// The 88-byte datagram of `m` (no checks: a device may send anything).
std::array<std::uint8_t, kPoseMessageSize> encode_pose(const PoseMessage& m);
/// The 72-byte datagram of `m`.
std::array<std::uint8_t, kFeedbackMessageSize> encode_feedback(const FeedbackMessage& m);

/// Outcome of decoding a datagram: the message, or the reason and a detail
/// sentence naming the offending field and value.
template <class M>
struct Decoded {
  std::optional<M> message;
  RejectReason reason = RejectReason::kMalformed;  ///< meaningful when !message
  std::string detail;                               ///< meaningful when !message
};

/// Decodes a pose datagram of `size` bytes. Checks only the framing (size,
/// magic, version, type); the values are checked by PoseStreamFilter.
Decoded<PoseMessage> decode_pose(const std::uint8_t* data, std::size_t size);
/// Decodes a feedback datagram of `size` bytes (framing checks, and a known status).
Decoded<FeedbackMessage> decode_feedback(const std::uint8_t* data, std::size_t size);

}  // namespace sflsh::teleop
