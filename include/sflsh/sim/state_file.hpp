#pragma once
// Checkpoints: a State saved to HDF5 and read back, so that a run can stop
// and resume bit-identically (`sflsh simulate --checkpoint F` / `--resume F`).
//
// Layout (names fixed; SI units):
//   /meta/format_version   3 (1: without /state/caches, read as well; 2: the
//                          contact patch's history without du_back_next, read
//                          when it holds no cache, else refused naming the version)
//   /meta/kind             "sflsh state"
//   /state/time            s
//   /state/bodies          (B,) body names, in model order
//   /state/<i>/bones       (24, 12) q_t: per bone the row-major rotation (9) then the translation (3)
//   /state/<i>/bones_prev  (24, 12) q_{t−1}
//   /state/<i>/z, z_prev   (3K,)    reduced soft DoFs at t and t − h
//   /state/caches/terms    (C,)     the model terms whose caches carry state
//                                   from step to step (TermCache::saved_state),
//                                   e.g. the contact patch's displacement
//   /state/caches/<j>/name          term j's name (checked against the scene)
//   /state/caches/<j>/values (N,)   its saved state
// Doubles are stored exactly (no float32), so a restored state equals the saved one.
// A caller may add groups of its own outside /meta and /state (a scene's
// tools: scene/scene_checkpoint.hpp), written into the same file before it
// is renamed into place and read in the same pass.
#include <functional>
#include <string>

#include "sflsh/io/hdf5_file.hpp"
#include "sflsh/sim/model.hpp"
#include "sflsh/sim/state.hpp"

namespace sflsh {

inline constexpr int kStateFormatVersion = 3;

/// Writes `state` of `model` to `path` (atomically: NAME.partial, then
/// renamed); `more`, when given, writes the caller's groups into the file.
void write_state(const std::string& path, const Model& model, const State& state,
                 const std::function<void(io::Hdf5File&)>& more = nullptr);

/// Reads a state saved for a model like `model`: the body names, their count
/// and each body's K must match, and each saved cache's term its name (else
/// one error naming the file and field). `more`, when given, reads the
/// caller's groups from the file (it may run twice: a first pass in a child
/// process guards against files on which libhdf5 crashes).
State read_state(const std::string& path, const Model& model,
                 const std::function<void(const io::Hdf5File&)>& more = nullptr);

}  // namespace sflsh
