#pragma once
// `sflsh simulate --use-file-betas`: an avatar of the shape stored in a motion
// file (AMASS `betas`), built like a given avatar: the same body model
// (Avatar::model_source, checked against Avatar::model_hash), the same tet
// mesh when the template-stage cache holds it, the same number of handles.
//
// Cache (in the template-stage cache folder, precompute.hpp):
//   template-<key>.h5  template stage, as `sflsh precompute` writes it; the
//                      entry whose model hash and tet elements equal the given
//                      avatar's is used, else the default template options
//                      (built and cached if needed);
//   avatar-<key>.h5    the shaped avatar, key = FNV-1a of (model hash, given
//                      avatar's tet elements, handle count, betas,
//                      avatar format version); reused when it reads back with
//                      the same model hash, handle count and betas.
#include <string>

#include "sflsh/asset/avatar.hpp"

namespace sflsh {

struct FileBetasReport {
  std::string model_source;    ///< body model used ("procedural", a path)
  int file_betas = 0;          ///< entries in the motion file
  int model_betas = 0;         ///< shape directions of the body model
  VecX betas;                  ///< what the avatar was built for (model_betas entries)
  std::string betas_note;      ///< "truncated ..." / "zero-padded ..." / ""
  int handles = 0;
  bool from_cache = false;     ///< shaped avatar read from the cache
  std::string avatar_path;     ///< the cached shaped avatar
  std::string template_path;   ///< template entry used ("" when from_cache)
  bool template_from_cache = false;
  std::string mesh_note;       ///< set when the mesh differs from the given avatar's
  double seconds = 0;          ///< wall time to get the avatar
  /// Lines for the log: betas used, model, handles, cache hit or build.
  std::string describe() const;
};

/// `betas` fitted to a model with `model_betas` shape directions: longer
/// vectors are truncated, shorter ones zero-padded; `note` (if given) says
/// which, "" when the sizes agree.
VecX fit_betas(const VecX& betas, int model_betas, std::string* note = nullptr);

/// The avatar of shape `betas` (fitted with fit_betas) built from the body
/// model `base` was built from, with base's handle count, from `cache_dir`
/// (template stage and shaped avatar) or built there. `base_path` names the
/// given avatar in messages and is the folder a relative model path is also
/// looked up in. Throws sflsh::Error when the model cannot be found or its
/// hash differs from base.model_hash.
Avatar avatar_for_file_betas(const Avatar& base, const std::string& base_path, const VecX& betas,
                             const std::string& cache_dir, FileBetasReport* report = nullptr);

}  // namespace sflsh
