#include "sflsh/teleop/stream_message.hpp"

#include <cstring>
#include <sstream>

namespace sflsh::teleop {
namespace {

static_assert(sizeof(double) == 8, "float64 fields");

// Little-endian field writer/reader (the wire format is little-endian on every host).
class Writer {
 public:
  explicit Writer(std::uint8_t* out) : p_(out) {}
  void u16(std::uint16_t v) { uint(v, 2); }
  void u32(std::uint32_t v) { uint(v, 4); }
  void u64(std::uint64_t v) { uint(v, 8); }
  void f64(double v) {
    std::uint64_t bits;
    std::memcpy(&bits, &v, 8);
    u64(bits);
  }
  void vec(const Vec3& v) {
    for (int i = 0; i < 3; ++i) f64(v[i]);
  }

 private:
  void uint(std::uint64_t v, int bytes) {
    for (int i = 0; i < bytes; ++i) *p_++ = static_cast<std::uint8_t>(v >> (8 * i));
  }
  std::uint8_t* p_;
};

class Reader {
 public:
  explicit Reader(const std::uint8_t* in) : p_(in) {}
  std::uint16_t u16() { return static_cast<std::uint16_t>(uint(2)); }
  std::uint32_t u32() { return static_cast<std::uint32_t>(uint(4)); }
  std::uint64_t u64() { return uint(8); }
  double f64() {
    const std::uint64_t bits = u64();
    double v;
    std::memcpy(&v, &bits, 8);
    return v;
  }
  Vec3 vec() {
    Vec3 v;
    for (int i = 0; i < 3; ++i) v[i] = f64();
    return v;
  }

 private:
  std::uint64_t uint(int bytes) {
    std::uint64_t v = 0;
    for (int i = 0; i < bytes; ++i) v |= static_cast<std::uint64_t>(*p_++) << (8 * i);
    return v;
  }
  const std::uint8_t* p_;
};

void write_header(Writer& w, std::uint16_t type) {
  w.u32(kStreamMagic);
  w.u16(kStreamVersion);
  w.u16(type);
}

// Checks the 8-byte header and the size; on success `r` stands after it.
template <class M>
bool check_header(Reader& r, std::size_t size, std::uint16_t want_type, std::size_t want_size,
                  std::uint16_t oldest_version, Decoded<M>& out) {
  auto reject = [&](RejectReason why, const std::string& detail) {
    out.reason = why;
    out.detail = detail;
    return false;
  };
  if (size < 8) return reject(RejectReason::kMalformed, std::to_string(size) + " bytes, shorter than the 8-byte header");
  const std::uint32_t magic = r.u32();
  if (magic != kStreamMagic) {
    std::ostringstream os;
    os << "magic 0x" << std::hex << magic << ", expected 0x" << kStreamMagic;
    return reject(RejectReason::kBadMagic, os.str());
  }
  const std::uint16_t version = r.u16();
  if (version < oldest_version || version > kStreamVersion)
    return reject(RejectReason::kBadVersion,
                  "version " + std::to_string(version) + ", expected " +
                      (oldest_version == kStreamVersion ? std::to_string(kStreamVersion)
                                                        : std::to_string(oldest_version) + ".." +
                                                              std::to_string(kStreamVersion)));
  const std::uint16_t type = r.u16();
  if (type != want_type)
    return reject(RejectReason::kWrongType,
                  "message type " + std::to_string(type) + ", expected " + std::to_string(want_type));
  if (size != want_size)
    return reject(RejectReason::kMalformed,
                  std::to_string(size) + " bytes, expected " + std::to_string(want_size));
  return true;
}

// Checks the framing and, when it is right, reads the body with `read_body(reader, message)`.
template <class M, class ReadBody>
Decoded<M> decode_framed(const std::uint8_t* data, std::size_t size, std::uint16_t type, std::size_t want_size,
                         std::uint16_t oldest_version, ReadBody read_body) {
  Decoded<M> out;
  Reader r(data);
  if (!check_header(r, size, type, want_size, oldest_version, out)) return out;
  M m;
  if (!read_body(r, m, out)) return out;
  out.message = m;
  return out;
}

}  // namespace

const char* to_string(RejectReason reason) {
  switch (reason) {
    case RejectReason::kMalformed: return "malformed";
    case RejectReason::kBadMagic: return "bad magic";
    case RejectReason::kBadVersion: return "bad version";
    case RejectReason::kWrongType: return "wrong type";
    case RejectReason::kNonFinite: return "non-finite";
    case RejectReason::kBadQuaternion: return "bad quaternion";
    case RejectReason::kBadClosure: return "bad closure";
    case RejectReason::kTimeNotIncreasing: return "time not increasing";
    case RejectReason::kJump: return "jump";
    case RejectReason::kOutOfOrder: return "out of order";
  }
  return "unknown";
}

std::array<std::uint8_t, kPoseMessageSize> encode_pose(const PoseMessage& m) {
  std::array<std::uint8_t, kPoseMessageSize> out{};
  Writer w(out.data());
  write_header(w, kPoseMessageType);
  w.u64(m.sequence);
  w.f64(m.sample.time);
  w.vec(m.sample.position);
  const Eigen::Quaterniond& q = m.sample.orientation;
  w.f64(q.w());
  w.f64(q.x());
  w.f64(q.y());
  w.f64(q.z());
  w.f64(m.sample.closure);
  return out;
}

std::array<std::uint8_t, kFeedbackMessageSize> encode_feedback(const FeedbackMessage& m) {
  std::array<std::uint8_t, kFeedbackMessageSize> out{};
  Writer w(out.data());
  write_header(w, kFeedbackMessageType);
  w.u64(m.sequence);
  w.f64(m.sim_time);
  w.vec(m.force);
  w.vec(m.torque);
  w.u32(static_cast<std::uint32_t>(m.status));
  w.u32(0);
  return out;
}

Decoded<PoseMessage> decode_pose(const std::uint8_t* data, std::size_t size) {
  return decode_framed<PoseMessage>(data, size, kPoseMessageType, kPoseMessageSize, kOldestPoseVersion,
                                    [](Reader& r, PoseMessage& m, Decoded<PoseMessage>&) {
    m.sequence = r.u64();
    m.sample.time = r.f64();
    m.sample.position = r.vec();
    const double w = r.f64(), x = r.f64(), y = r.f64(), z = r.f64();
    m.sample.orientation = Eigen::Quaterniond(w, x, y, z);
    m.sample.closure = r.f64();
    return true;
  });
}

Decoded<FeedbackMessage> decode_feedback(const std::uint8_t* data, std::size_t size) {
  return decode_framed<FeedbackMessage>(
      data, size, kFeedbackMessageType, kFeedbackMessageSize, kStreamVersion,
      [](Reader& r, FeedbackMessage& m, Decoded<FeedbackMessage>& out) {
        m.sequence = r.u64();
        m.sim_time = r.f64();
        m.force = r.vec();
        m.torque = r.vec();
        const std::uint32_t status = r.u32();
        if (status >= kNumFeedbackStatus) {
          out.reason = RejectReason::kMalformed;
          out.detail = "status " + std::to_string(status) + ", expected 0 (running), 1 (ramping in) or 2 (ended)";
          return false;
        }
        m.status = static_cast<FeedbackStatus>(status);
        return true;
      });
}

}  // namespace sflsh::teleop
