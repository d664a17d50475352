#pragma once
// Errors are exceptions whose message names what failed and where (file,
// dataset/key/line, expected value). The CLI prints the message on one line and
// exits non-zero.
#include <sstream>
#include <stdexcept>
#include <string>

namespace sflsh {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& what) : std::runtime_error(what) {}
};

namespace detail {
inline void append(std::ostringstream&) {}
template <class T, class... R>
void append(std::ostringstream& os, const T& t, const R&... r) {
  os << t;
  append(os, r...);
}
}  // namespace detail

/// Builds a message from the arguments (streamed in order) and throws sflsh::Error.
template <class... A>
[[noreturn]] void fail(const A&... args) {
  std::ostringstream os;
  detail::append(os, args...);
  throw Error(os.str());
}

/// Throws sflsh::Error built from `args` unless `cond` holds.
template <class... A>
void require(bool cond, const A&... args) {
  if (!cond) fail(args...);
}

}  // namespace sflsh
