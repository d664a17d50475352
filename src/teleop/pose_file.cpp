#include "sflsh/teleop/pose_file.hpp"

#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

#include "sflsh/core/error.hpp"
#include "sflsh/io/atomic_output.hpp"

namespace sflsh::teleop {
namespace {

// The nine values of a row in file-comment order.
constexpr int kNumFields = 9;
const std::array<const char*, kNumFields> kCsvColumns = {"time", "x", "y", "z", "qw", "qx", "qy", "qz", "closure"};
using Row = std::array<double, kNumFields>;

std::string trim(const std::string& s) {
  std::size_t b = 0, e = s.size();
  while (b < e && std::isspace(static_cast<unsigned char>(s[b]))) ++b;
  while (e > b && std::isspace(static_cast<unsigned char>(s[e - 1]))) --e;
  return s.substr(b, e - b);
}

// Where in the input an error is: "NAME line N".
struct Where {
  const std::string& name;
  int line;
  std::string at(const std::string& field) const {
    return name + " line " + std::to_string(line) + ", field '" + field + "'";
  }
};

// A finite decimal number, the whole of `text` (nan and inf are named as not finite).
double parse_number(const std::string& text, const Where& w, const std::string& field) {
  const std::string t = trim(text);
  char* end = nullptr;
  const double v = t.empty() ? 0.0 : std::strtod(t.c_str(), &end);
  // strtod also reads hexadecimal ("0x1p3"): not a number in these files.
  if (t.empty() || end != t.c_str() + t.size() || t.find_first_of("xX") != std::string::npos)
    fail(w.at(field), ": expected a number, got '", t, "'");
  if (!std::isfinite(v)) fail(w.at(field), ": expected a finite number, got '", t, "'");
  return v;
}

// Checks a row's values and appends the sample (times strictly increasing).
// `time_field` is the time's name in the format ("time" or "t").
void add_sample(const Row& r, const Where& w, const char* time_field, std::vector<PoseSample>* out) {
  PoseSample s;
  s.time = r[0];
  s.position = Vec3(r[1], r[2], r[3]);
  s.orientation = Eigen::Quaterniond(r[4], r[5], r[6], r[7]);
  s.closure = r[8];
  const double norm = s.orientation.norm();
  if (std::abs(norm - 1.0) > 1e-3)
    fail(w.at("q"), ": quaternion norm ", norm, ", expected a unit quaternion (within 1e-3)");
  normalize_unless_unit(s.orientation);
  if (s.closure < 0.0 || s.closure > kMaxClosure)
    fail(w.at("closure"), ": ", s.closure, " rad, expected a jaw opening angle in [0, pi]");
  if (!out->empty() && !(s.time > out->back().time))
    fail(w.at(time_field), ": ", s.time, " s is not after the previous sample's ", out->back().time,
         " s (times must be strictly increasing)");
  out->push_back(s);
}

std::vector<std::string> split_commas(const std::string& line) {
  std::vector<std::string> parts;
  std::stringstream ss(line);
  std::string p;
  while (std::getline(ss, p, ',')) parts.push_back(p);
  if (!line.empty() && line.back() == ',') parts.emplace_back();
  return parts;
}

bool skipped(const std::string& line) { return line.empty() || line[0] == '#'; }

std::vector<PoseSample> parse_csv(const std::string& text, const std::string& name) {
  std::vector<PoseSample> out;
  std::istringstream in(text);
  std::string raw;
  std::array<int, kNumFields> column_of{};  // field -> column index
  bool have_header = false;
  std::size_t num_columns = 0;
  for (int line_no = 1; std::getline(in, raw); ++line_no) {
    const std::string line = trim(raw);
    if (skipped(line)) continue;
    const Where w{name, line_no};
    const std::vector<std::string> cells = split_commas(line);
    if (!have_header) {
      std::map<std::string, int> seen;
      for (std::size_t c = 0; c < cells.size(); ++c) {
        const std::string col = trim(cells[c]);
        int field = -1;
        for (int f = 0; f < kNumFields; ++f)
          if (col == kCsvColumns[f]) field = f;
        if (field < 0)
          fail(name, " line ", line_no, ": unknown column '", col,
               "' in the header, expected time,x,y,z,qw,qx,qy,qz,closure");
        if (seen.count(col)) fail(name, " line ", line_no, ": column '", col, "' appears twice in the header");
        seen[col] = static_cast<int>(c);
        column_of[field] = static_cast<int>(c);
      }
      for (const char* col : kCsvColumns)
        if (!seen.count(col))
          fail(name, " line ", line_no, ": header lacks the column '", col,
               "', expected time,x,y,z,qw,qx,qy,qz,closure");
      num_columns = cells.size();
      have_header = true;
      continue;
    }
    if (cells.size() != num_columns)
      fail(name, " line ", line_no, ": ", cells.size(), " values, expected ", num_columns, " (one per header column)");
    Row r;
    for (int f = 0; f < kNumFields; ++f) r[f] = parse_number(cells[column_of[f]], w, kCsvColumns[f]);
    add_sample(r, w, "time", &out);
  }
  require(have_header, name, ": no header line, expected time,x,y,z,qw,qx,qy,qz,closure");
  return out;
}

// A minimal reader for the one JSON object shape of a pose line.
class JsonLine {
 public:
  JsonLine(const std::string& s, const Where& w) : s_(s), w_(w) {}

  Row parse() {
    const std::array<const char*, 4> keys = {"t", "p", "q", "closure"};
    const std::array<int, 4> sizes = {1, 3, 4, 1};
    const std::array<int, 4> first = {0, 1, 4, 8};  // index in Row
    std::array<bool, 4> seen{};
    Row r{};
    expect('{');
    if (peek() == '}') fail(where(), ": empty object, expected keys t, p, q, closure");
    for (;;) {
      const std::string key = string();
      int k = -1;
      for (int i = 0; i < 4; ++i)
        if (key == keys[i]) k = i;
      if (k < 0) fail(w_.at(key), ": unknown key, expected t, p, q, closure");
      if (seen[k]) fail(w_.at(key), ": key appears twice");
      seen[k] = true;
      expect(':');
      if (sizes[k] == 1) {
        r[first[k]] = number(key);
      } else {
        expect('[');
        for (int i = 0; i < sizes[k]; ++i) {
          if (peek() == ']') fail(w_.at(key), ": ", i, " numbers, expected ", sizes[k]);
          if (i > 0) expect(',');
          r[first[k] + i] = number(key);
        }
        if (peek() != ']') fail(w_.at(key), ": more than ", sizes[k], " numbers, expected ", sizes[k]);
        expect(']');
      }
      if (peek() == ',') {
        ++i_;
        continue;
      }
      expect('}');
      break;
    }
    skip_ws();
    if (i_ != s_.size()) fail(where(), ": unexpected text after the object at column ", i_ + 1);
    for (int k = 0; k < 4; ++k)
      if (!seen[k]) fail(w_.at(keys[k]), ": missing key");
    return r;
  }

 private:
  std::string where() const { return w_.name + " line " + std::to_string(w_.line); }
  void skip_ws() {
    while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_]))) ++i_;
  }
  char peek() {
    skip_ws();
    return i_ < s_.size() ? s_[i_] : '\0';
  }
  void expect(char c) {
    if (peek() != c)
      fail(where(), ": expected '", c, "' at column ", i_ + 1,
           i_ < s_.size() ? std::string(", got '") + s_[i_] + "'" : std::string(", got the end of the line"));
    ++i_;
  }
  std::string string() {
    expect('"');
    const std::size_t end = s_.find('"', i_);
    if (end == std::string::npos) fail(where(), ": unterminated string at column ", i_);
    std::string key = s_.substr(i_, end - i_);
    i_ = end + 1;
    return key;
  }
  double number(const std::string& key) {
    skip_ws();
    std::size_t e = i_;
    while (e < s_.size() && s_[e] != ',' && s_[e] != ']' && s_[e] != '}' &&
           !std::isspace(static_cast<unsigned char>(s_[e])))
      ++e;
    const double v = parse_number(s_.substr(i_, e - i_), w_, key);
    i_ = e;
    return v;
  }

  const std::string& s_;
  const Where& w_;
  std::size_t i_ = 0;
};

std::vector<PoseSample> parse_jsonl(const std::string& text, const std::string& name) {
  std::vector<PoseSample> out;
  std::istringstream in(text);
  std::string raw;
  for (int line_no = 1; std::getline(in, raw); ++line_no) {
    const std::string line = trim(raw);
    if (skipped(line)) continue;
    const Where w{name, line_no};
    add_sample(JsonLine(line, w).parse(), w, "t", &out);
  }
  return out;
}

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

}  // namespace

PoseFileFormat pose_file_format(const std::string& path) {
  const std::string ext = io::lower_extension(path);
  if (ext == ".csv") return PoseFileFormat::kCsv;
  if (ext == ".jsonl" || ext == ".ndjson") return PoseFileFormat::kJsonLines;
  fail(path, ": unknown pose file extension '", ext, "', expected .csv, .jsonl or .ndjson");
}

std::vector<PoseSample> parse_pose_text(const std::string& text, PoseFileFormat format, const std::string& name) {
  std::vector<PoseSample> out = format == PoseFileFormat::kCsv ? parse_csv(text, name) : parse_jsonl(text, name);
  require(!out.empty(), name, ": no pose samples, expected at least one row");
  return out;
}

std::vector<PoseSample> read_pose_file(const std::string& path) {
  const PoseFileFormat format = pose_file_format(path);
  std::ifstream in(path, std::ios::binary);
  require(in.good(), path, ": cannot open the pose file");
  std::ostringstream ss;
  ss << in.rdbuf();
  return parse_pose_text(ss.str(), format, path);
}

std::string pose_file_header(PoseFileFormat format) {
  return format == PoseFileFormat::kCsv ? "time,x,y,z,qw,qx,qy,qz,closure" : "";
}

std::string format_pose_row(const PoseSample& s, PoseFileFormat format) {
  const Eigen::Quaterniond& q = s.orientation;
  const Vec3& p = s.position;
  if (format == PoseFileFormat::kCsv)
    return num(s.time) + "," + num(p.x()) + "," + num(p.y()) + "," + num(p.z()) + "," + num(q.w()) + "," +
           num(q.x()) + "," + num(q.y()) + "," + num(q.z()) + "," + num(s.closure);
  return "{\"t\":" + num(s.time) + ",\"p\":[" + num(p.x()) + "," + num(p.y()) + "," + num(p.z()) + "],\"q\":[" +
         num(q.w()) + "," + num(q.x()) + "," + num(q.y()) + "," + num(q.z()) + "],\"closure\":" + num(s.closure) +
         "}";
}

void write_pose_file(const std::string& path, const std::vector<PoseSample>& samples) {
  const PoseFileFormat format = pose_file_format(path);
  io::write_text_file(path, [&](std::ostream& f) {
    const std::string header = pose_file_header(format);
    if (!header.empty()) f << header << '\n';
    for (const PoseSample& s : samples) f << format_pose_row(s, format) << '\n';
  });
}

}  // namespace sflsh::teleop
