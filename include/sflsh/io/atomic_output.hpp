#pragma once
// Writing a file so that readers never see a half-written one: the data goes
// to "<path>.partial" next to the target (same file system) and is renamed
// over <path> by commit(). Without commit() (an exception, an early return)
// the partial file is removed, so a failed job leaves nothing behind.
#include <functional>
#include <iosfwd>
#include <string>

namespace sflsh::io {

class AtomicOutput {
 public:
  /// Prepares to write `path`; creates missing parent folders.
  explicit AtomicOutput(std::string path);
  ~AtomicOutput();  ///< Removes the partial file unless committed.
  AtomicOutput(const AtomicOutput&) = delete;
  AtomicOutput& operator=(const AtomicOutput&) = delete;

  /// Where to write the data ("<path>.partial").
  const std::string& temp_path() const { return temp_path_; }
  /// The final path.
  const std::string& path() const { return path_; }
  /// Renames the partial file over the final path (throws if it is missing).
  void commit();

 private:
  std::string path_, temp_path_;
  bool committed_ = false;
};

/// Writes the text file `path` through an AtomicOutput: `write` fills the
/// stream, then the file is put in place. Throws "PATH: cannot write" when
/// the file cannot be opened and "PATH: write failed" when writing fails
/// (nothing is left at `path` then, nor a partial file).
void write_text_file(const std::string& path, const std::function<void(std::ostream&)>& write);

/// Checks, before any work starts, that a file can be written at `path`: it is
/// not a folder, and its nearest existing ancestor is a folder in which a file
/// can be created (tried with a temporary file that is removed at once).
/// Creates nothing. Throws "OPTION PATH: ..." naming the reason.
void check_output_file(const std::string& path, const std::string& option);
/// The same for an output folder: `path` is an existing folder, or does not
/// exist and can be created (nothing is created here).
void check_output_folder(const std::string& path, const std::string& option);

/// Lower-case extension of `path` including the dot (".obj"), "" if none.
std::string lower_extension(const std::string& path);

}  // namespace sflsh::io
