#include "sflsh/io/joint_export.hpp"

#include <fstream>

#include "sflsh/core/error.hpp"
#include "sflsh/io/atomic_output.hpp"

namespace sflsh::io {

namespace {

/// JSON string literal (names are plain identifiers, but quote safely anyway).
std::string json_quote(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) < 0x20) continue;
    out += c;
  }
  return out + "\"";
}

}  // namespace

void write_joints(const std::string& path, const Points& joints, const std::vector<std::string>& names,
                  const std::vector<int>& parents) {
  const std::string ext = lower_extension(path);
  require(ext == ".csv" || ext == ".json", path, ": unknown joint file format '", ext,
          "'; supported: .csv, .json");
  require(names.size() == size_t(joints.rows()) && parents.size() == size_t(joints.rows()), path,
          ": joints has ", joints.rows(), " rows but ", names.size(), " names and ", parents.size(), " parents");
  require(joints.allFinite(), path, ": joint positions contain NaN or Inf");

  AtomicOutput out(path);
  std::ofstream os(out.temp_path());
  require(bool(os), path, ": cannot open ", out.temp_path(), " for writing");
  os.precision(9);
  if (ext == ".csv") {
    os << "index,name,parent,x,y,z\n";
    for (Eigen::Index j = 0; j < joints.rows(); ++j)
      os << j << ',' << names[j] << ',' << parents[j] << ',' << joints(j, 0) << ',' << joints(j, 1) << ','
         << joints(j, 2) << '\n';
  } else {
    os << "{\n  \"format_version\": 1,\n  \"units\": \"metres\",\n  \"joints\": [\n";
    for (Eigen::Index j = 0; j < joints.rows(); ++j)
      os << "    {\"index\": " << j << ", \"name\": " << json_quote(names[j]) << ", \"parent\": " << parents[j]
         << ", \"position\": [" << joints(j, 0) << ", " << joints(j, 1) << ", " << joints(j, 2) << "]}"
         << (j + 1 < joints.rows() ? ",\n" : "\n");
    os << "  ]\n}\n";
  }
  os.close();
  require(bool(os), path, ": write failed (disk full?)");
  out.commit();
}

}  // namespace sflsh::io
