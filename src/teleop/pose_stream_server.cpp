#include "sflsh/teleop/pose_stream_server.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <iostream>

#include "sflsh/core/error.hpp"

namespace sflsh::teleop {
namespace {

std::string address_text(const sockaddr_in& a) {
  char buf[INET_ADDRSTRLEN] = {0};
  inet_ntop(AF_INET, &a.sin_addr, buf, sizeof buf);
  return std::string(buf) + ":" + std::to_string(ntohs(a.sin_port));
}

}  // namespace

PoseStreamServer::PoseStreamServer(PoseStreamServerOptions options)
    : options_(std::move(options)), filter_(options_.checks) {
  require(options_.port >= 0 && options_.port <= 65535, "teleop stream port ", options_.port,
          ": expected 0 (pick a free one) or 1..65535");
  require(options_.max_datagrams_per_poll >= 1, "teleop stream max_datagrams_per_poll ",
          options_.max_datagrams_per_poll, ": expected >= 1");
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) fail("teleop stream: cannot open a UDP socket: ", std::strerror(errno));
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  addr.sin_port = htons(static_cast<std::uint16_t>(options_.port));
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
    const std::string why = std::strerror(errno);
    ::close(fd_);
    fail("teleop stream: cannot bind UDP 127.0.0.1:", options_.port, ": ", why);
  }
  // Room for a burst of ~1000 pose datagrams between two polls.
  const int rcvbuf = 1 << 20;
  ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof rcvbuf);
  socklen_t len = sizeof addr;
  ::getsockname(fd_, reinterpret_cast<sockaddr*>(&addr), &len);
  port_ = ntohs(addr.sin_port);
}

PoseStreamServer::~PoseStreamServer() {
  if (fd_ >= 0) ::close(fd_);
}

std::optional<StreamSample> PoseStreamServer::poll(double now, std::vector<StreamSample>* accepted) {
  std::optional<StreamSample> newest;
  // Larger than any valid message so that oversize datagrams are seen (and
  // rejected as malformed) rather than silently truncated to a valid size.
  std::uint8_t buf[2048];
  for (int read = 0; read < options_.max_datagrams_per_poll;) {
    sockaddr_in from{};
    socklen_t from_len = sizeof from;
    const ssize_t n = ::recvfrom(fd_, buf, sizeof buf, MSG_TRUNC, reinterpret_cast<sockaddr*>(&from), &from_len);
    if (n < 0) {
      if (errno == EINTR) continue;
      break;  // EAGAIN: drained (other errors: nothing more to read either)
    }
    ++read;
    pending_from_.assign(reinterpret_cast<const std::uint8_t*>(&from),
                         reinterpret_cast<const std::uint8_t*>(&from) + sizeof from);
    // With MSG_TRUNC, n is the real datagram size even when it exceeded buf.
    handle(buf, static_cast<std::size_t>(n), address_text(from), now, accepted, &newest);
  }
  return newest;
}

void PoseStreamServer::handle(const std::uint8_t* data, std::size_t size, const std::string& from, double now,
                              std::vector<StreamSample>* accepted, std::optional<StreamSample>* newest) {
  ++counters_.received;
  std::optional<RejectReason> why;
  std::string detail;
  const Decoded<PoseMessage> d = decode_pose(data, size);
  std::uint64_t seq = 0;
  if (!d.message) {
    why = d.reason;
    detail = d.detail;
  } else {
    seq = d.message->sequence;
    why = filter_.check(*d.message, &detail);
  }
  if (why) {
    ++counters_.rejected[static_cast<int>(*why)];
    std::string line = "teleop stream: rejected datagram " + std::to_string(counters_.received) + " from " + from;
    if (d.message) line += " (sequence " + std::to_string(seq) + ")";
    line += ": " + std::string(to_string(*why)) + ": " + detail + "; ";
    line += last_good_ ? "holding the pose of sequence " + std::to_string(last_good_->sequence)
                       : std::string("no pose received yet");
    if (options_.log)
      options_.log(line);
    else
      std::cerr << line << '\n';
    return;
  }
  ++counters_.accepted;
  StreamSample s;
  s.sequence = filter_.last_good()->sequence;
  s.sample = filter_.last_good()->sample;
  s.receive_time = now;
  last_good_ = s;
  *newest = s;
  reply_to_ = pending_from_;
  if (accepted) accepted->push_back(s);
}

bool PoseStreamServer::send_feedback(const Vec3& force, const Vec3& torque, double sim_time, FeedbackStatus status) {
  if (!last_good_ || reply_to_.size() != sizeof(sockaddr_in)) return false;
  FeedbackMessage m;
  m.sequence = last_good_->sequence;
  m.sim_time = sim_time;
  m.force = force;
  m.torque = torque;
  m.status = status;
  const auto bytes = encode_feedback(m);
  const ssize_t n = ::sendto(fd_, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(reply_to_.data()),
                             sizeof(sockaddr_in));
  if (n != static_cast<ssize_t>(bytes.size())) return false;
  ++feedback_sent_;
  return true;
}

bool PoseStreamServer::wait_readable(double timeout) const {
  pollfd p{fd_, POLLIN, 0};
  const int ms = int(std::max(0.0, timeout) * 1000.0 + 0.5);
  return ::poll(&p, 1, ms) > 0 && (p.revents & POLLIN);
}

}  // namespace sflsh::teleop
