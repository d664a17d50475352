#include "sflsh/io/atomic_output.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <system_error>

#include <unistd.h>

#include "sflsh/core/error.hpp"

namespace sflsh::io {

namespace fs = std::filesystem;

AtomicOutput::AtomicOutput(std::string path) : path_(std::move(path)), temp_path_(path_ + ".partial") {
  require(!path_.empty(), "output path is empty");
  const fs::path parent = fs::path(path_).parent_path();
  if (!parent.empty()) {
    std::error_code ec;
    fs::create_directories(parent, ec);
    if (ec) fail(path_, ": cannot create folder ", parent.string(), ": ", ec.message());
  }
}

AtomicOutput::~AtomicOutput() {
  if (committed_) return;
  std::error_code ec;
  fs::remove(temp_path_, ec);
}

void AtomicOutput::commit() {
  std::error_code ec;
  require(fs::exists(temp_path_, ec), path_, ": nothing was written (", temp_path_, " is missing)");
  fs::rename(temp_path_, path_, ec);
  if (ec) fail(path_, ": cannot rename ", temp_path_, " into place: ", ec.message());
  committed_ = true;
}

void write_text_file(const std::string& path, const std::function<void(std::ostream&)>& write) {
  AtomicOutput out(path);
  {
    std::ofstream f(out.temp_path());
    if (!f) fail(path, ": cannot write");
    write(f);
    f.close();
    if (!f) fail(path, ": write failed");
  }
  out.commit();
}

namespace {

// The nearest existing ancestor of `path` must be a folder we can create files in.
void check_writable_ancestor(const fs::path& path, const std::string& what) {
  std::error_code ec;
  fs::path dir = path.parent_path();
  while (!dir.empty() && !fs::exists(dir, ec)) dir = dir.parent_path();
  if (dir.empty()) dir = ".";
  if (!fs::is_directory(dir, ec)) fail(what, ": ", dir.string(), " is not a folder");
  std::string probe = (dir / ".sflsh-write-check-XXXXXX").string();
  const int fd = mkstemp(probe.data());
  if (fd < 0) fail(what, ": cannot create files in folder ", dir.string());
  close(fd);
  unlink(probe.c_str());
}

}  // namespace

void check_output_file(const std::string& path, const std::string& option) {
  const std::string what = option + " " + path;
  require(!path.empty(), option, ": output path is empty");
  std::error_code ec;
  if (fs::is_directory(path, ec)) fail(what, ": is a folder; give a file name");
  check_writable_ancestor(fs::path(path), what);
}

void check_output_folder(const std::string& path, const std::string& option) {
  const std::string what = option + " " + path;
  require(!path.empty(), option, ": output folder is empty");
  std::error_code ec;
  if (fs::exists(path, ec) && !fs::is_directory(path, ec)) fail(what, ": exists and is not a folder");
  // Probe inside the folder itself when it exists, else in its nearest existing ancestor.
  check_writable_ancestor(fs::path(path) / "x", what);
}

std::string lower_extension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext;
}

}  // namespace sflsh::io
