#pragma once
// The semantic checks of a live pose stream, independent of the socket: a
// decoded sample is accepted or rejected with a reason; after a rejection the
// last good sample is held. A bad packet never reaches the simulation.
#include <array>
#include <cstdint>
#include <optional>
#include <string>

#include "sflsh/teleop/stream_message.hpp"

namespace sflsh::teleop {

struct PoseStreamCheckOptions {
  /// Fastest believable tool motion (m/s): a sample whose position is farther
  /// from the last accepted one than max_speed × (time difference) is a jump.
  /// Default 20 m/s (a hand moves at most a few m/s).
  double max_speed = 20.0;
  /// Largest accepted | |q| - 1 |; smaller deviations are normalized away.
  /// Default 1e-3.
  double quaternion_tolerance = 1e-3;
};

/// Stream counters: every datagram is received, then accepted or rejected for
/// exactly one reason.
struct PoseStreamCounters {
  long received = 0;
  long accepted = 0;
  std::array<long, kNumRejectReasons> rejected{};  ///< indexed by RejectReason
  long rejected_total() const;
  /// One line: "received R, accepted A, rejected X (malformed m, jump j, ...)"
  /// listing only the non-zero reasons.
  std::string describe() const;
};

/// The stream checks of one device, in order: finite values, unit quaternion
/// (normalized when within tolerance), closure in [0, pi], sequence number
/// after the last accepted one, device time after the last accepted one,
/// speed from the last accepted sample at most max_speed. A device restarting
/// its sequence numbers or clock from zero is therefore rejected until it
/// passes the held values: make a new filter (server) for a new session.
class PoseStreamFilter {
 public:
  explicit PoseStreamFilter(const PoseStreamCheckOptions& options = {});

  /// Checks `m`. On acceptance returns nothing, replaces the held sample by
  /// `m` (with its quaternion normalized) and returns; on rejection returns
  /// the reason and sets *detail to a sentence naming the field and value.
  std::optional<RejectReason> check(const PoseMessage& m, std::string* detail);

  /// The last accepted message (the held pose), if any.
  const std::optional<PoseMessage>& last_good() const { return last_; }
  const PoseStreamCheckOptions& options() const { return options_; }

 private:
  PoseStreamCheckOptions options_;
  std::optional<PoseMessage> last_;
};

}  // namespace sflsh::teleop
