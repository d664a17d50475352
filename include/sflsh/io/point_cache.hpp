#pragma once
// Animated surfaces as files other tools open:
//  - PC2 point caches (the Blender / 3ds Max "Point Cache 2" format; Blender's
//    Mesh Cache modifier reads it on top of the rest mesh exported as OBJ):
//      char[12] "POINTCACHE2\0", int32 version = 1, int32 numPoints,
//      float32 startFrame, float32 sampleRate, int32 numSamples,
//      then numSamples * numPoints * (float32 x, y, z), little-endian.
//    sampleRate is the spacing between samples in frames (1 = every frame).
//  - mesh sequences: one OBJ/PLY/glb per frame from a printf-style pattern
//    such as "frames/body_%04d.obj".
#include <cstdint>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "sflsh/core/types.hpp"
#include "sflsh/io/atomic_output.hpp"

namespace sflsh::io {

/// Streams a PC2 file frame by frame (constant memory) into "<path>.partial";
/// commit() writes the frame count into the header and moves the file into
/// place. Destroyed without commit(), it leaves nothing behind.
class Pc2Writer {
 public:
  /// `num_points` points per frame; `start_frame` and `sample_rate` (frames
  /// between samples) go to the header as float32.
  Pc2Writer(const std::string& path, int num_points, double start_frame = 0.0, double sample_rate = 1.0);
  ~Pc2Writer();
  Pc2Writer(const Pc2Writer&) = delete;
  Pc2Writer& operator=(const Pc2Writer&) = delete;

  /// Appends one frame: P (#points by 3, metres), stored as float32.
  void add_frame(const Points& P);
  int num_frames() const { return num_frames_; }
  /// Finalizes the header and renames the file into place.
  void commit();

 private:
  AtomicOutput out_;
  std::ofstream os_;
  int num_points_;
  int num_frames_ = 0;
  std::vector<float> buffer_;
};

/// A PC2 file in memory.
struct PointCache {
  double start_frame = 0.0;
  double sample_rate = 1.0;
  std::vector<Points> frames;  ///< numSamples entries of #points by 3
};

/// Writes all frames at once (each #points by 3; at least one frame).
void write_pc2(const std::string& path, const std::vector<Points>& frames, double start_frame = 0.0,
               double sample_rate = 1.0);
/// Reads a PC2 file; throws naming the path on a bad magic / version or a
/// size that does not match the header.
PointCache read_pc2(const std::string& path);

/// Fills a printf-style pattern holding exactly one integer directive
/// ("%d" or "%0Nd", e.g. "out/frame_%04d.obj"); "%%" is a literal percent.
/// Throws naming the pattern if it has none, several, or another directive.
std::string format_frame_path(const std::string& pattern, int frame);

/// Writes a mesh per frame through write_mesh (format from the pattern's
/// extension), every file atomic.
class MeshSequenceWriter {
 public:
  /// `pattern` as in format_frame_path; F is #F by 3, shared by all frames.
  MeshSequenceWriter(std::string pattern, Triangles F);
  /// Writes frame `index` (V: #V by 3, optional per-vertex colours); returns its path.
  std::string write_frame(int index, const Points& V, const Points& colors = Points());

 private:
  std::string pattern_;
  Triangles F_;
};

}  // namespace sflsh::io
