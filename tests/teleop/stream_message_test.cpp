#include "sflsh/teleop/stream_message.hpp"

#include <gtest/gtest.h>

#include <cstring>

namespace sflsh::teleop {
namespace {

PoseMessage distinct_pose() {
  PoseMessage m;
  m.sequence = 0x0102030405060708ull;
  m.sample.time = 12.375;
  m.sample.position = Vec3(0.125, -0.5, 1.75);
  m.sample.orientation = Eigen::Quaterniond(0.5, -0.5, 0.5, 0.5);
  m.sample.closure = 0.625;
  return m;
}

double f64_at(const std::uint8_t* p) {  // the host is little-endian (x86-64)
  double v;
  std::memcpy(&v, p, 8);
  return v;
}

TEST(StreamMessage, PoseLayoutMatchesTheDocumentedOffsets) {
  const auto b = encode_pose(distinct_pose());
  ASSERT_EQ(b.size(), 88u);
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(b.data()), 4), "SFTP");
  EXPECT_EQ(b[4], 2);  // version, little-endian uint16
  EXPECT_EQ(b[5], 0);
  EXPECT_EQ(b[6], 1);  // type pose
  EXPECT_EQ(b[7], 0);
  for (int i = 0; i < 8; ++i) EXPECT_EQ(b[8 + i], 8 - i);  // 0x0102030405060708 little-endian
  EXPECT_EQ(f64_at(&b[16]), 12.375);
  EXPECT_EQ(f64_at(&b[24]), 0.125);
  EXPECT_EQ(f64_at(&b[32]), -0.5);
  EXPECT_EQ(f64_at(&b[40]), 1.75);
  EXPECT_EQ(f64_at(&b[48]), 0.5);   // qw
  EXPECT_EQ(f64_at(&b[56]), -0.5);  // qx
  EXPECT_EQ(f64_at(&b[64]), 0.5);
  EXPECT_EQ(f64_at(&b[72]), 0.5);
  EXPECT_EQ(f64_at(&b[80]), 0.625);
}

TEST(StreamMessage, PoseRoundTrip) {
  const PoseMessage m = distinct_pose();
  const auto b = encode_pose(m);
  const auto d = decode_pose(b.data(), b.size());
  ASSERT_TRUE(d.message) << d.detail;
  EXPECT_EQ(d.message->sequence, m.sequence);
  EXPECT_EQ(d.message->sample.time, 12.375);
  EXPECT_EQ(d.message->sample.position, Vec3(0.125, -0.5, 1.75));
  EXPECT_EQ(d.message->sample.orientation.coeffs(), Eigen::Quaterniond(0.5, -0.5, 0.5, 0.5).coeffs());
  EXPECT_EQ(d.message->sample.closure, 0.625);
}

TEST(StreamMessage, FeedbackRoundTripAndLayout) {
  FeedbackMessage m;
  m.sequence = 77;
  m.sim_time = 3.25;
  m.force = Vec3(1.5, -2.5, 3.5);
  m.torque = Vec3(-0.25, 0.75, -1.125);
  m.status = FeedbackStatus::kEnded;
  const auto b = encode_feedback(m);
  ASSERT_EQ(b.size(), 80u);
  EXPECT_EQ(b[4], 2);  // version 2: the status field
  EXPECT_EQ(b[6], 2);  // type feedback
  EXPECT_EQ(b[8], 77);
  EXPECT_EQ(f64_at(&b[16]), 3.25);
  EXPECT_EQ(f64_at(&b[24]), 1.5);
  EXPECT_EQ(f64_at(&b[64]), -1.125);
  EXPECT_EQ(b[72], 2);  // status "ended", little-endian uint32
  for (int i = 73; i < 80; ++i) EXPECT_EQ(b[i], 0) << "byte " << i;
  const auto d = decode_feedback(b.data(), b.size());
  ASSERT_TRUE(d.message) << d.detail;
  EXPECT_EQ(d.message->sequence, 77u);
  EXPECT_EQ(d.message->sim_time, 3.25);
  EXPECT_EQ(d.message->force, m.force);
  EXPECT_EQ(d.message->torque, m.torque);
  EXPECT_EQ(d.message->status, FeedbackStatus::kEnded);
  m.status = FeedbackStatus::kRampIn;
  const auto r = encode_feedback(m);
  EXPECT_EQ(r[72], 1);
  EXPECT_EQ(decode_feedback(r.data(), r.size()).message->status, FeedbackStatus::kRampIn);
}

TEST(StreamMessage, FeedbackWithAnUnknownStatusOrTheOldLayoutIsRejected) {
  FeedbackMessage m;
  auto b = encode_feedback(m);
  b[72] = 3;  // no such status
  auto d = decode_feedback(b.data(), b.size());
  EXPECT_FALSE(d.message);
  EXPECT_EQ(d.reason, RejectReason::kMalformed);
  EXPECT_NE(d.detail.find("status 3"), std::string::npos) << d.detail;
  b = encode_feedback(m);
  b[4] = 1;  // version 1's feedback had no status: a version-1 reader must not take this one
  d = decode_feedback(b.data(), b.size());
  EXPECT_EQ(d.reason, RejectReason::kBadVersion);
  EXPECT_FALSE(decode_feedback(encode_feedback(m).data(), 72).message);  // the old 72-byte size
}

TEST(StreamMessage, APoseOfVersionOneIsStillRead) {
  auto b = encode_pose(distinct_pose());
  b[4] = 1;
  const auto d = decode_pose(b.data(), b.size());
  ASSERT_TRUE(d.message) << d.detail;
  EXPECT_EQ(d.message->sample.closure, 0.625);
}

TEST(StreamMessage, FramingErrorsAreNamed) {
  auto b = encode_pose(distinct_pose());
  auto reason = [](const std::uint8_t* p, std::size_t n) {
    const auto d = decode_pose(p, n);
    EXPECT_FALSE(d.message);
    EXPECT_FALSE(d.detail.empty());
    return d.reason;
  };
  EXPECT_EQ(reason(b.data(), 5), RejectReason::kMalformed);   // shorter than the header
  EXPECT_EQ(reason(b.data(), 87), RejectReason::kMalformed);  // truncated body
  std::vector<std::uint8_t> longer(b.begin(), b.end());
  longer.push_back(0);
  EXPECT_EQ(reason(longer.data(), longer.size()), RejectReason::kMalformed);
  auto bad = b;
  bad[0] = 'X';
  EXPECT_EQ(reason(bad.data(), bad.size()), RejectReason::kBadMagic);
  bad = b;
  bad[4] = 3;
  EXPECT_EQ(reason(bad.data(), bad.size()), RejectReason::kBadVersion);
  bad[4] = 0;
  EXPECT_EQ(reason(bad.data(), bad.size()), RejectReason::kBadVersion);
  const auto fb = encode_feedback(FeedbackMessage{});
  EXPECT_EQ(reason(fb.data(), fb.size()), RejectReason::kWrongType);
  EXPECT_FALSE(decode_feedback(b.data(), b.size()).message);
}

}  // namespace
}  // namespace sflsh::teleop
