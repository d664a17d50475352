#include "sflsh/io/point_cache.hpp"

#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>

#include "sflsh/core/error.hpp"
#include "sflsh/io/mesh_export.hpp"

namespace sflsh::io {

namespace {

constexpr char kPc2Magic[12] = "POINTCACHE2";  // 11 characters + the terminating '\0'
constexpr std::int32_t kPc2Version = 1;
constexpr std::streamoff kPc2HeaderBytes = 32;
constexpr std::streamoff kPc2NumSamplesOffset = 28;

// PC2 is little-endian; these (de)serialize independent of the host.
void put_le32(char* out, std::uint32_t x) {
  for (int i = 0; i < 4; ++i) out[i] = char((x >> (8 * i)) & 0xff);
}
std::uint32_t get_le32(const char* in) {
  std::uint32_t x = 0;
  for (int i = 0; i < 4; ++i) x |= std::uint32_t(static_cast<unsigned char>(in[i])) << (8 * i);
  return x;
}
std::uint32_t float_bits(float f) {
  std::uint32_t u;
  std::memcpy(&u, &f, 4);
  return u;
}
float bits_float(std::uint32_t u) {
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}

}  // namespace

Pc2Writer::Pc2Writer(const std::string& path, int num_points, double start_frame, double sample_rate)
    : out_(path), num_points_(num_points) {
  require(num_points > 0, path, ": a point cache needs at least one point, got ", num_points);
  require(std::isfinite(start_frame) && std::isfinite(sample_rate) && sample_rate > 0, path,
          ": start frame must be finite and sample rate positive, got ", start_frame, " and ", sample_rate);
  os_.open(out_.temp_path(), std::ios::binary | std::ios::trunc);
  require(bool(os_), path, ": cannot open ", out_.temp_path(), " for writing");
  char header[kPc2HeaderBytes];
  std::memcpy(header, kPc2Magic, 12);
  put_le32(header + 12, std::uint32_t(kPc2Version));
  put_le32(header + 16, std::uint32_t(num_points));
  put_le32(header + 20, float_bits(float(start_frame)));
  put_le32(header + 24, float_bits(float(sample_rate)));
  put_le32(header + 28, 0);  // numSamples, patched by commit()
  os_.write(header, kPc2HeaderBytes);
  buffer_.resize(size_t(num_points) * 3);
}

Pc2Writer::~Pc2Writer() {
  if (os_.is_open()) os_.close();  // out_ then removes the partial file unless committed
}

void Pc2Writer::add_frame(const Points& P) {
  require(os_.is_open(), out_.path(), ": add_frame after commit");
  require(P.rows() == num_points_, out_.path(), ": frame ", num_frames_, " has ", P.rows(), " points, expected ",
          num_points_);
  require(P.allFinite(), out_.path(), ": frame ", num_frames_, " contains NaN or Inf");
  std::vector<char> bytes(buffer_.size() * 4);
  for (Eigen::Index i = 0; i < P.rows(); ++i)
    for (int c = 0; c < 3; ++c) put_le32(bytes.data() + (size_t(i) * 3 + size_t(c)) * 4, float_bits(float(P(i, c))));
  os_.write(bytes.data(), std::streamsize(bytes.size()));
  require(bool(os_), out_.path(), ": write failed at frame ", num_frames_, " (disk full?)");
  ++num_frames_;
}

void Pc2Writer::commit() {
  require(os_.is_open(), out_.path(), ": commit called twice");
  require(num_frames_ > 0, out_.path(), ": no frames were added");
  char n[4];
  put_le32(n, std::uint32_t(num_frames_));
  os_.seekp(kPc2NumSamplesOffset);
  os_.write(n, 4);
  os_.close();
  require(bool(os_), out_.path(), ": write failed (disk full?)");
  out_.commit();
}

void write_pc2(const std::string& path, const std::vector<Points>& frames, double start_frame, double sample_rate) {
  require(!frames.empty(), path, ": no frames to write");
  Pc2Writer writer(path, int(frames.front().rows()), start_frame, sample_rate);
  for (const Points& P : frames) writer.add_frame(P);
  writer.commit();
}

PointCache read_pc2(const std::string& path) {
  std::ifstream is(path, std::ios::binary);
  require(bool(is), path, ": cannot open for reading");
  char header[kPc2HeaderBytes];
  is.read(header, kPc2HeaderBytes);
  require(is.gcount() == kPc2HeaderBytes, path, ": truncated PC2 header (", is.gcount(), " of 32 bytes)");
  require(std::memcmp(header, kPc2Magic, 12) == 0, path, ": not a PC2 file (expected magic \"POINTCACHE2\")");
  const std::int32_t version = std::int32_t(get_le32(header + 12));
  require(version == kPc2Version, path, ": PC2 version ", version, ", expected 1");
  const std::int32_t num_points = std::int32_t(get_le32(header + 16));
  const std::int32_t num_samples = std::int32_t(get_le32(header + 28));
  require(num_points >= 0 && num_samples >= 0, path, ": negative numPoints (", num_points, ") or numSamples (",
          num_samples, ")");
  PointCache cache;
  cache.start_frame = bits_float(get_le32(header + 20));
  cache.sample_rate = bits_float(get_le32(header + 24));

  const std::uintmax_t expected = std::uintmax_t(kPc2HeaderBytes) + std::uintmax_t(num_points) * 12u * std::uintmax_t(num_samples);
  const std::uintmax_t actual = std::filesystem::file_size(path);
  require(actual == expected, path, ": file has ", actual, " bytes, header (", num_points, " points x ", num_samples,
          " samples) implies ", expected);
  std::vector<char> bytes(size_t(num_points) * 12);
  cache.frames.reserve(size_t(num_samples));
  for (int s = 0; s < num_samples; ++s) {
    is.read(bytes.data(), std::streamsize(bytes.size()));
    require(is.gcount() == std::streamsize(bytes.size()), path, ": truncated at sample ", s);
    Points P(num_points, 3);
    for (int i = 0; i < num_points; ++i)
      for (int c = 0; c < 3; ++c) P(i, c) = bits_float(get_le32(bytes.data() + (size_t(i) * 3 + size_t(c)) * 4));
    cache.frames.push_back(std::move(P));
  }
  return cache;
}

std::string format_frame_path(const std::string& pattern, int frame) {
  std::string out;
  int directives = 0;
  for (size_t i = 0; i < pattern.size(); ++i) {
    if (pattern[i] != '%') {
      out += pattern[i];
      continue;
    }
    if (i + 1 < pattern.size() && pattern[i + 1] == '%') {
      out += '%';
      ++i;
      continue;
    }
    // %d or %0Nd
    size_t j = i + 1;
    const bool zero = j < pattern.size() && pattern[j] == '0';
    if (zero) ++j;
    int width = 0;
    while (j < pattern.size() && std::isdigit(static_cast<unsigned char>(pattern[j])) && width < 100)
      width = width * 10 + (pattern[j++] - '0');
    require(j < pattern.size() && pattern[j] == 'd', "frame pattern '", pattern,
            "': only %d or %0Nd (e.g. %04d) is allowed, found '", pattern.substr(i, j - i + 1), "'");
    std::string num = std::to_string(frame < 0 ? -static_cast<long>(frame) : static_cast<long>(frame));
    const size_t sign = frame < 0 ? 1 : 0;
    if (num.size() + sign < size_t(width)) num.insert(0, size_t(width) - num.size() - sign, zero ? '0' : ' ');
    out += (frame < 0 ? "-" : "") + num;
    ++directives;
    i = j;
  }
  require(directives == 1, "frame pattern '", pattern, "' must hold exactly one %d or %0Nd (e.g. frame_%04d.obj), found ",
          directives);
  return out;
}

MeshSequenceWriter::MeshSequenceWriter(std::string pattern, Triangles F) : pattern_(std::move(pattern)), F_(std::move(F)) {
  // Validate before any frame is simulated, not at the first write.
  format_frame_path(pattern_, 0);
  require_mesh_export_extension(pattern_, "frame pattern '" + pattern_ + "'");
}

std::string MeshSequenceWriter::write_frame(int index, const Points& V, const Points& colors) {
  const std::string path = format_frame_path(pattern_, index);
  write_mesh(path, V, F_, colors);
  return path;
}

}  // namespace sflsh::io
