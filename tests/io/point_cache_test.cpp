#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "sflsh/core/error.hpp"
#include "sflsh/io/mesh_export.hpp"
#include "sflsh/io/point_cache.hpp"
#include "test_support.hpp"

namespace sflsh::io {
namespace {

namespace fs = std::filesystem;

std::vector<Points> some_frames(int frames, int points) {
  std::vector<Points> out;
  for (int f = 0; f < frames; ++f) {
    Points P(points, 3);
    for (int i = 0; i < points; ++i) P.row(i) << 0.1 * i + f, std::sin(i + 0.3 * f), -0.01 * i * f;
    out.push_back(P);
  }
  return out;
}

TEST(PointCache, Pc2RoundTripAndLayout) {
  test::TempDir dir;
  const auto frames = some_frames(3, 5);
  write_pc2(dir.file("a.pc2"), frames, 10.0, 0.5);
  EXPECT_EQ(fs::file_size(dir.file("a.pc2")), 32u + 3u * 5u * 12u);
  char magic[12];
  std::ifstream(dir.file("a.pc2"), std::ios::binary).read(magic, 12);
  EXPECT_EQ(std::string(magic, 12), std::string("POINTCACHE2\0", 12));

  const PointCache pc = read_pc2(dir.file("a.pc2"));
  EXPECT_EQ(pc.start_frame, 10.0);
  EXPECT_EQ(pc.sample_rate, 0.5);
  ASSERT_EQ(pc.frames.size(), 3u);
  for (size_t f = 0; f < 3; ++f) {
    ASSERT_EQ(pc.frames[f].rows(), 5);
    EXPECT_LT((pc.frames[f] - frames[f]).cwiseAbs().maxCoeff(), 1e-6);  // float32 storage
  }
}

TEST(PointCache, StreamingWriterLeavesNothingWithoutCommit) {
  test::TempDir dir;
  {
    Pc2Writer w(dir.file("b.pc2"), 4);
    w.add_frame(Points::Zero(4, 3));
    EXPECT_THROW(w.add_frame(Points::Zero(3, 3)), Error);
    Points nan = Points::Zero(4, 3);
    nan(1, 1) = std::nan("");
    EXPECT_THROW(w.add_frame(nan), Error);
    EXPECT_EQ(w.num_frames(), 1);
  }
  EXPECT_TRUE(fs::is_empty(dir.path()));
  EXPECT_THROW(write_pc2(dir.file("c.pc2"), {}), Error);
}

TEST(PointCache, ReaderRejectsBadFiles) {
  test::TempDir dir;
  write_pc2(dir.file("a.pc2"), some_frames(2, 3));
  fs::resize_file(dir.file("a.pc2"), 32 + 2 * 3 * 12 - 4);
  EXPECT_THROW(read_pc2(dir.file("a.pc2")), Error);
  std::ofstream(dir.file("b.pc2"), std::ios::binary) << "NOTACACHE___0000000000000000000000";
  EXPECT_THROW(read_pc2(dir.file("b.pc2")), Error);
  EXPECT_THROW(read_pc2(dir.file("missing.pc2")), Error);
}

TEST(PointCache, FramePattern) {
  EXPECT_EQ(format_frame_path("out/f_%04d.obj", 7), "out/f_0007.obj");
  EXPECT_EQ(format_frame_path("f%d.ply", 123), "f123.ply");
  EXPECT_EQ(format_frame_path("100%%_%03d.obj", 5), "100%_005.obj");
  EXPECT_EQ(format_frame_path("f_%02d.obj", 1234), "f_1234.obj");
  EXPECT_THROW(format_frame_path("f.obj", 1), Error);
  EXPECT_THROW(format_frame_path("f_%d_%d.obj", 1), Error);
  EXPECT_THROW(format_frame_path("f_%s.obj", 1), Error);
}

TEST(PointCache, MeshSequence) {
  test::TempDir dir;
  Triangles F(1, 3);
  F << 0, 1, 2;
  MeshSequenceWriter seq(dir.file("seq/frame_%03d.obj"), F);
  const auto frames = some_frames(3, 3);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(seq.write_frame(i, frames[size_t(i)]), dir.file("seq/frame_00" + std::to_string(i) + ".obj"));
  const ImportedMesh m = read_mesh(dir.file("seq/frame_002.obj"));
  EXPECT_EQ(m.faces.rows(), 1);
  EXPECT_THROW(MeshSequenceWriter(dir.file("frame_%03d.xyz"), F), Error);
  EXPECT_THROW(MeshSequenceWriter(dir.file("frame.obj"), F), Error);
}

}  // namespace
}  // namespace sflsh::io
