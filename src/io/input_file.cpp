#include "sflsh/io/input_file.hpp"

#include <filesystem>
#include <fstream>

#include "sflsh/core/error.hpp"

namespace sflsh::io {

void require_input_file(const std::string& path, const std::string& what) {
  namespace fs = std::filesystem;
  const std::string name = what.empty() ? path : what + " " + path;
  require(!path.empty(), what, ": the file name is empty");
  std::error_code ec;
  const fs::file_status s = fs::status(path, ec);
  if (!fs::exists(s)) fail(name, ": file not found");
  if (fs::is_directory(s)) fail(name, ": is a folder, expected a file");
  if (!std::ifstream(path, std::ios::binary)) fail(name, ": cannot be read (permissions?)");
}

}  // namespace sflsh::io
