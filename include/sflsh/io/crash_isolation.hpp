#pragma once
// Containment of crashes inside third-party readers.
//
// Fuzzing found damaged files on which Debian's libhdf5 1.10 and assimp 5.2 crash in their own
// code, past any check this project can make before calling them: libhdf5 sizes a buffer from a
// header, its malloc fails, and it copies into the null pointer (a local heap, a contiguous
// dataset; tests/fuzz_regressions/{avatar,result}_h5/), and assimp's triangulation aborted on an
// internal assertion (tests/fuzz_regressions/mesh/; the mesh reader now splits polygons itself
// and checks PLY headers first, but keeps the probe). A reader of a file that comes from outside
// therefore first parses it in a forked child process: if the child dies by a signal, the file
// is refused with one error naming it, and this process never runs the crashing code. If the
// child ends normally the file is read here (a second parse: ~10–100 ms for an avatar).
#include <functional>
#include <string>

namespace sflsh::io {

/// Runs `probe` in a forked child (unless the environment sets SFLSH_READ_IN_PROCESS=1, as
/// scripts/fuzz.sh does so that the fuzzers see every crash, the library's too). Throws sflsh::Error naming `what` if the child is killed by
/// a signal (or exits abnormally), or if it runs longer than SFLSH_READ_PROBE_SECONDS (default
/// 120 s; the child is then killed); returns otherwise, also when `probe` threw (the caller's own
/// read then throws the same error). Returns without probing if fork is unavailable.
void probe_in_child_process(const std::string& what, const std::function<void()>& probe);

/// The readers' pattern: `read` probed in a child first (above), then run here; returns its result.
template <class Read>
auto read_in_child_first(const std::string& what, Read&& read) -> decltype(read()) {
  probe_in_child_process(what, [&] { read(); });
  return read();
}

}  // namespace sflsh::io
