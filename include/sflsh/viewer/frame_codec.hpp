#pragma once
// The viewer's frames (server -> page): one binary WebSocket message per
// displayed frame, little-endian, at the display rate (<= 30 fps).
//
//   offset size  field
//        0    4  magic     uint32 0x46564653 (the bytes "SFVF")
//        4    2  version   uint16 1
//        6    2  kind      uint16 1 = full, 2 = delta (only the vertices that changed
//                          since the previous frame sent to this client)
//        8    4  number    uint32 frame number (server counter)
//       12    4  V         uint32 skin vertices (ViewerScene::rest rows)
//       16    4  N         uint32 entries below: V (full) or the changed count (delta)
//       20    4  O         uint32 objects (ViewerScene::objects)
//       24    4  J         uint32 joints
//       28    4  L         uint32 bytes of the trailing JSON
//       32    8  time      float64 s
//       40    4  legend    float32 m, |u| of a magnitude count 255
//       44    4  reserved  0
//       48  4N   index     uint32 vertex indices (delta only)
//          6N   position  uint16 x y z per entry: box_min + q / 65535 · (box_max − box_min)
//           N   magnitude uint8 |u| per entry: q / 255 · legend (clamped at legend)
//               zero padding to a multiple of 4 bytes
//          28O  poses     float32 px py pz qw qx qy qz per object (object -> world)
//          12J  joints    float32 x y z
//           L   info      UTF-8 JSON: {"t","seq","driver","clients","paused","rtf","step_ms",
//                         "terms":[[name, ms]...],"stiffness","resets","steps","max_u_mm","frame","speed",
//                         "tool":{"force":[N],"device":[m],"quat":[w,x,y,z],"closure","contact","anchors"},
//                         "tools":[{"pose":[px,py,pz,qw,qx,qy,qz],"force":[N],"torque":[N·m],"closure"}],
//                         "contacts":[{"force":[N],"point":[m],"depth_mm","active"}]}
//                         ("tool": the driven tool, live; "tools": every tool, live and playback;
//                         "contacts": every ViewerScene contact, live and playback)
// 16-bit positions keep a 2 m box to 0.03 mm and the default avatar (~9k
// vertices) at 63 kB per full frame (1.9 MB/s at 30 fps); deltas are smaller
// whenever part of the skin is still.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "sflsh/core/types.hpp"
#include "sflsh/scene/simulation_run.hpp"
#include "sflsh/sim/configuration.hpp"
#include "sflsh/viewer/viewer_scene.hpp"

namespace sflsh::viewer {

constexpr std::uint32_t kFrameMagic = 0x46564653u;
constexpr std::uint16_t kFrameVersion = 1;
constexpr std::uint16_t kFullFrame = 1, kDeltaFrame = 2;
constexpr std::size_t kFrameHeaderBytes = 48;

/// What the panels show besides the geometry.
struct ViewerStats {
  double rtf = 0;        ///< real-time factor over the last second (live)
  double step_ms = 0;    ///< mean wall time per step over the last second (ms)
  std::vector<std::string> term_names;  ///< per-term split of step_ms
  std::vector<double> term_ms;          ///< ms per step, same order
  bool paused = false;
  double stiffness_scale = 1;  ///< live: the soft tissue's stiffness scale (SceneSession::stiffness_scale)
  long resets = 0;              ///< live: resets applied so far
  long steps = 0;
  bool has_tool = false;        ///< the driven tool's readout below is meaningful
  Vec3 force = Vec3::Zero();    ///< N, world: the bodies' force on the tool
  Vec3 device = Vec3::Zero();   ///< m, world: the device position the tool is driven to
  Eigen::Quaterniond device_orientation = Eigen::Quaterniond::Identity();  ///< the device's (tool -> world)
  double closure = 0;           ///< rad
  bool contact = false;         ///< the tool touches the flesh (force > 0 or anchors)
  int anchors = 0;
  double max_displacement = 0;  ///< m, max |u| over the skin
  int frame_index = -1;         ///< playback: the result frame shown
  double speed = 1;             ///< playback speed
};

/// One displayed frame as the simulation (or the player) publishes it.
struct ViewerFrame {
  double time = 0;              ///< s
  Points positions;             ///< #V by 3 posed skin (m, world)
  VecX displacement;            ///< #V soft displacement magnitudes |u| (m)
  Points joints;                ///< #J by 3 (m, world); may be empty
  std::vector<Isometry> object_poses;  ///< one per ViewerScene object
  std::vector<ToolFrame> tools;        ///< one per ViewerScene tool (pose, closure, force, torque)
  std::vector<ContactFrame> contacts;  ///< one per ViewerScene contact (force on the body, point, depth, samples)
  ViewerStats stats;
};

/// The frame's skin as sent: 3 uint16 per vertex, then 1 uint8 per vertex.
struct QuantizedSkin {
  std::vector<std::uint16_t> position;  ///< 3V
  std::vector<std::uint8_t> magnitude;  ///< V
};

/// Quantizes positions to the scene's box (clamped) and |u| to [0, legend_max].
QuantizedSkin quantize(const ViewerFrame& frame, const ViewerScene& scene);

/// Per-client fields of a frame.
struct FrameEnvelope {
  std::uint32_t number = 0;
  std::uint64_t seq = 0;  ///< the last control message applied before this frame (echo)
  bool driver = false;    ///< this client drives the tool
  int clients = 1;
};

/// The message for one client: a delta against *last_sent when that is
/// smaller than a full frame and *last_sent is not empty, else full; then
/// *last_sent = `skin`.
std::string encode_frame(const ViewerFrame& frame, const QuantizedSkin& skin, const ViewerScene& scene,
                         const FrameEnvelope& envelope, QuantizedSkin* last_sent);

/// A frame as the page sees it.
struct DecodedFrame {
  std::uint16_t kind = 0;
  std::uint32_t number = 0;
  double time = 0;
  Points positions;   ///< #V by 3, dequantized (m)
  VecX displacement;  ///< #V, m
  std::vector<Isometry> object_poses;
  Points joints;
  std::string info;   ///< the JSON
};

/// Decodes a message onto *state (the previous frames' skin; empty before the
/// first, which must be full). Throws sflsh::Error naming the field on a
/// malformed message.
DecodedFrame decode_frame(std::string_view bytes, const ViewerScene& scene, QuantizedSkin* state);

}  // namespace sflsh::viewer
