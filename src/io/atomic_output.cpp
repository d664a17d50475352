#include "sflsh/io/atomic_output.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <system_error>

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

std::string lower_extension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext;
}

}  // namespace sflsh::io
