#include "sflsh/motion/bvh.hpp"

#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

#include "sflsh/core/error.hpp"

namespace sflsh {
namespace {

constexpr double kDegToRad = 3.14159265358979323846 / 180.0;
constexpr int kMaxJoints = 100000;
constexpr long long kMaxFrames = 100'000'000;

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f'; }
bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

// Shortens a token for messages (binary junk must not flood the terminal).
std::string shown(std::string_view tok) {
  std::string s(tok.substr(0, 24));
  for (char& c : s)
    if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) c = '?';
  return tok.size() > 24 ? s + "..." : s;
}

// A whitespace tokenizer over the whole file that knows its line number.
class Scanner {
 public:
  Scanner(std::string_view text, const std::string& name) : s_(text), name_(name) {}

  /// Next token, or "" at the end of the text.
  std::string_view next() {
    skip_space();
    const size_t b = pos_;
    while (pos_ < s_.size() && !is_space(s_[pos_])) ++pos_;
    return s_.substr(b, pos_ - b);
  }
  std::string_view peek() {
    const size_t p = pos_;
    const int l = line_;
    std::string_view t = next();
    pos_ = p;
    line_ = l;
    return t;
  }
  int line() const { return line_; }
  bool at_end() {
    skip_space();
    return pos_ >= s_.size();
  }

  [[noreturn]] void error(const std::string& what) const { error_at(line_, what); }
  [[noreturn]] void error_at(int line, const std::string& what) const { fail(name_, ":", line, ": ", what); }

  /// Parses `tok` as a finite double; throws naming `what` otherwise.
  double number(std::string_view tok, const char* what) const {
    double v = 0;
    if (!parse_double(tok, &v)) error(std::string("expected ") + what + ", found '" + shown(tok) + "'");
    return v;
  }
  static bool parse_double(std::string_view tok, double* v) {
    if (!tok.empty() && tok[0] == '+') tok.remove_prefix(1);
    if (tok.empty()) return false;
    const auto r = std::from_chars(tok.data(), tok.data() + tok.size(), *v);
    return r.ec == std::errc() && r.ptr == tok.data() + tok.size() && std::isfinite(*v);
  }
  long long integer(std::string_view tok, const char* what) const {
    long long v = 0;
    const auto r = std::from_chars(tok.data(), tok.data() + tok.size(), v);
    if (tok.empty() || r.ec != std::errc() || r.ptr != tok.data() + tok.size())
      error(std::string("expected ") + what + ", found '" + shown(tok) + "'");
    return v;
  }

  /// Moves past the rest of the current line; throws if it holds anything.
  void expect_end_of_line(const char* after) {
    while (pos_ < s_.size() && is_blank(s_[pos_])) ++pos_;
    if (pos_ < s_.size() && s_[pos_] != '\n') {
      const size_t b = pos_;
      while (pos_ < s_.size() && !is_space(s_[pos_])) ++pos_;
      error(std::string("unexpected '") + shown(s_.substr(b, pos_ - b)) + "' after " + after);
    }
  }

  /// Reads the values of one frame line into out[0..count); throws when the
  /// line holds another number of values or a non-number.
  void read_frame(double* out, int count, int frame, int frames) {
    // Skip blank lines.
    for (;;) {
      while (pos_ < s_.size() && is_blank(s_[pos_])) ++pos_;
      if (pos_ < s_.size() && s_[pos_] == '\n') {
        ++pos_;
        ++line_;
        continue;
      }
      break;
    }
    if (pos_ >= s_.size())
      error("the motion block ends after " + std::to_string(frame) + " of " + std::to_string(frames) +
            " frames (truncated file, or 'Frames:' says too many)");
    int k = 0;
    for (;;) {
      while (pos_ < s_.size() && is_blank(s_[pos_])) ++pos_;
      if (pos_ >= s_.size() || s_[pos_] == '\n') break;
      const size_t b = pos_;
      while (pos_ < s_.size() && !is_space(s_[pos_])) ++pos_;
      const std::string_view tok = s_.substr(b, pos_ - b);
      if (k >= count)
        error("frame " + std::to_string(frame + 1) + " has more than the " + std::to_string(count) +
              " values the HIERARCHY declares");
      if (!parse_double(tok, &out[k]))
        error("frame " + std::to_string(frame + 1) + ", value " + std::to_string(k + 1) +
              ": expected a finite number, found '" + shown(tok) + "'");
      ++k;
    }
    if (k != count)
      error("frame " + std::to_string(frame + 1) + " has " + std::to_string(k) + " values, expected " +
            std::to_string(count) + " (the channels declared in HIERARCHY)");
  }

 private:
  void skip_space() {
    while (pos_ < s_.size() && is_space(s_[pos_])) {
      if (s_[pos_] == '\n') ++line_;
      ++pos_;
    }
  }
  std::string_view s_;
  const std::string& name_;
  size_t pos_ = 0;
  int line_ = 1;
};

bool channel_from_name(std::string_view n, BvhChannel* c) {
  static const std::pair<std::string_view, BvhChannel> names[] = {
      {"Xposition", BvhChannel::Xposition}, {"Yposition", BvhChannel::Yposition},
      {"Zposition", BvhChannel::Zposition}, {"Xrotation", BvhChannel::Xrotation},
      {"Yrotation", BvhChannel::Yrotation}, {"Zrotation", BvhChannel::Zrotation}};
  for (const auto& [s, v] : names)
    if (s == n) {
      *c = v;
      return true;
    }
  return false;
}

// Parses "OFFSET x y z" (the keyword already consumed).
Vec3 read_offset(Scanner& sc) {
  Vec3 v;
  for (int i = 0; i < 3; ++i) v[i] = sc.number(sc.next(), "an OFFSET coordinate (3 numbers)");
  return v;
}

void read_channels(Scanner& sc, BvhJoint& joint) {
  if (!joint.channels.empty()) sc.error("joint '" + joint.name + "' has a second CHANNELS line");
  const long long n = sc.integer(sc.next(), "a channel count (0 to 6) after CHANNELS");
  if (n < 0 || n > 6) sc.error("CHANNELS count " + std::to_string(n) + " of joint '" + joint.name +
                               "': expected 0 to 6");
  bool seen[6] = {false, false, false, false, false, false};
  for (long long i = 0; i < n; ++i) {
    const std::string_view tok = sc.next();
    BvhChannel c;
    if (!channel_from_name(tok, &c))
      sc.error("joint '" + joint.name + "': expected " + std::to_string(n) +
               " channel names (Xposition Yposition Zposition Xrotation Yrotation Zrotation), found '" +
               shown(tok) + "' as channel " + std::to_string(i + 1));
    if (seen[int(c)])
      sc.error("joint '" + joint.name + "': channel '" + std::string(tok) +
               "' appears twice (rotation order must name each axis once)");
    seen[int(c)] = true;
    joint.channels.push_back(c);
  }
}

void parse_hierarchy(Scanner& sc, BvhMotion& m) {
  if (sc.next() != "HIERARCHY") sc.error("expected 'HIERARCHY' at the start of a BVH file");
  std::vector<int> open;           // stack of joints whose '{' is open
  std::vector<int> open_line;      // where they were opened
  std::vector<bool> has_offset;
  for (;;) {
    const std::string_view tok = sc.next();
    const int line = sc.line();  // tokens never span lines
    if (tok.empty()) {
      if (open.empty()) sc.error("file ends before the MOTION block");
      sc.error("file ends inside the HIERARCHY: joint '" + m.joints[open.back()].name + "' opened at line " +
               std::to_string(open_line.back()) + " has no closing '}'");
    }
    if (tok == "ROOT" || tok == "JOINT") {
      if (tok == "ROOT" && !open.empty()) sc.error("'ROOT' inside joint '" + m.joints[open.back()].name + "'");
      if (tok == "JOINT" && open.empty()) sc.error("'JOINT' outside any ROOT (missing 'ROOT' or an extra '}')");
      if (m.joints.size() >= size_t(kMaxJoints)) sc.error("more than " + std::to_string(kMaxJoints) + " joints");
      const std::string_view name = sc.next();
      if (name.empty() || name == "{" || name == "}") sc.error(std::string("expected a joint name after ") +
                                                                std::string(tok));
      BvhJoint j;
      j.name = std::string(name);
      j.parent = open.empty() ? -1 : open.back();
      if (sc.next() != "{") sc.error("expected '{' after " + std::string(tok) + " " + j.name);
      open.push_back(int(m.joints.size()));
      open_line.push_back(line);
      has_offset.push_back(false);
      m.joints.push_back(std::move(j));
    } else if (tok == "End") {
      if (open.empty()) sc.error("'End Site' outside any joint");
      BvhJoint& j = m.joints[open.back()];
      if (sc.next() != "Site") sc.error("expected 'Site' after 'End'");
      if (sc.next() != "{") sc.error("expected '{' after 'End Site'");
      if (sc.next() != "OFFSET") sc.error("expected 'OFFSET' in the End Site of joint '" + j.name + "'");
      j.end_site = read_offset(sc);
      j.has_end_site = true;
      if (sc.next() != "}") sc.error("expected '}' closing the End Site of joint '" + j.name + "'");
    } else if (tok == "OFFSET") {
      if (open.empty()) sc.error("'OFFSET' outside any joint");
      if (has_offset[open.back()]) sc.error("joint '" + m.joints[open.back()].name + "' has a second OFFSET");
      m.joints[open.back()].offset = read_offset(sc);
      has_offset[open.back()] = true;
    } else if (tok == "CHANNELS") {
      if (open.empty()) sc.error("'CHANNELS' outside any joint");
      read_channels(sc, m.joints[open.back()]);
    } else if (tok == "}") {
      if (open.empty()) sc.error("unexpected '}' (no joint is open)");
      if (!has_offset[open.back()]) sc.error("joint '" + m.joints[open.back()].name + "' has no OFFSET");
      open.pop_back();
      open_line.pop_back();
    } else if (tok == "MOTION") {
      if (!open.empty())
        sc.error("'MOTION' while joint '" + m.joints[open.back()].name + "' opened at line " +
                 std::to_string(open_line.back()) + " has no closing '}'");
      if (m.joints.empty()) sc.error("'MOTION' before any ROOT joint");
      return;
    } else {
      sc.error("expected ROOT, JOINT, OFFSET, CHANNELS, End Site, '}' or MOTION, found '" + shown(tok) + "'");
    }
  }
}

// Reads "<label> value" where the label may be glued to the value ("Frames:12").
std::string_view labelled_value(Scanner& sc, std::string_view label, const char* what) {
  std::string_view tok = sc.next();
  if (tok.substr(0, label.size()) != label) sc.error(std::string("expected '") + std::string(label) + "' " + what);
  tok.remove_prefix(label.size());
  return tok.empty() ? sc.next() : tok;
}

void parse_motion(Scanner& sc, BvhMotion& m, size_t text_size) {
  const std::string_view frames_tok = labelled_value(sc, "Frames:", "after MOTION");
  const int frames_line = sc.line();
  const long long frames = sc.integer(frames_tok, "a frame count after 'Frames:'");
  if (frames < 1 || frames > kMaxFrames)
    sc.error("'Frames: " + std::to_string(frames) + "': expected 1 to " + std::to_string(kMaxFrames));
  if (sc.next() != "Frame") sc.error("expected 'Frame Time:' after the 'Frames:' line");
  const double dt = sc.number(labelled_value(sc, "Time:", "after 'Frame'"), "'Frame Time' in seconds");
  if (!(dt > 0)) sc.error("'Frame Time' must be positive, found " + std::to_string(dt));
  sc.expect_end_of_line("the frame time");
  m.num_frames = int(frames);
  m.frame_time = dt;
  // Each value takes at least two bytes (digit + separator): a count the file
  // cannot hold is a truncated file, caught before allocating for it.
  const double needed = double(frames) * m.num_channels;
  if (needed > double(text_size) / 2 + 1)
    sc.error_at(frames_line, "'Frames: " + std::to_string(frames) + "' with " + std::to_string(m.num_channels) +
                                 " channels needs more values than the file holds (truncated?)");
  m.values.resize(size_t(frames) * m.num_channels);
  for (int f = 0; f < m.num_frames; ++f) sc.read_frame(&m.values[size_t(f) * m.num_channels], m.num_channels, f,
                                                        m.num_frames);
  if (!sc.at_end()) sc.error("unexpected data after the last of the " + std::to_string(frames) +
                             " frames ('Frames:' at line " + std::to_string(frames_line) + " says too few?)");
}

}  // namespace

BvhMotion parse_bvh(std::string_view text, const std::string& name) {
  Scanner sc(text, name);
  BvhMotion m;
  m.path = name;
  parse_hierarchy(sc, m);
  int col = 0;
  for (auto& j : m.joints) {
    j.first_channel = col;
    col += int(j.channels.size());
  }
  m.num_channels = col;
  if (col == 0) sc.error("the HIERARCHY declares no CHANNELS at all");
  parse_motion(sc, m, text.size());
  return m;
}

BvhMotion read_bvh(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  require(bool(in), path, ": cannot open BVH file");
  std::ostringstream ss;
  ss << in.rdbuf();
  require(!in.bad(), path, ": read error");
  return parse_bvh(ss.str(), path);
}

Eigen::Quaterniond BvhMotion::local_rotation(int joint, int frame) const {
  const BvhJoint& j = joints[joint];
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  for (size_t c = 0; c < j.channels.size(); ++c) {
    const double a = value(frame, j.first_channel + int(c)) * kDegToRad;
    switch (j.channels[c]) {
      case BvhChannel::Xrotation: q = q * Eigen::AngleAxisd(a, Vec3::UnitX()); break;
      case BvhChannel::Yrotation: q = q * Eigen::AngleAxisd(a, Vec3::UnitY()); break;
      case BvhChannel::Zrotation: q = q * Eigen::AngleAxisd(a, Vec3::UnitZ()); break;
      default: break;
    }
  }
  return q.normalized();
}

Vec3 BvhMotion::local_translation(int joint, int frame) const {
  const BvhJoint& j = joints[joint];
  Vec3 t = j.offset;
  for (size_t c = 0; c < j.channels.size(); ++c) {
    const double v = value(frame, j.first_channel + int(c));
    switch (j.channels[c]) {
      case BvhChannel::Xposition: t.x() += v; break;
      case BvhChannel::Yposition: t.y() += v; break;
      case BvhChannel::Zposition: t.z() += v; break;
      default: break;
    }
  }
  return t;
}

}  // namespace sflsh
