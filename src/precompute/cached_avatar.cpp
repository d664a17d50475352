#include "sflsh/precompute/cached_avatar.hpp"

#include <unistd.h>

#include <cmath>
#include <filesystem>

#include "sflsh/asset/avatar_file.hpp"
#include "sflsh/body/body_model_io.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/precompute/batch_precompute.hpp"

namespace sflsh {

namespace fs = std::filesystem;

CachedAvatar cached_avatar(const BodyModel& model, const VecX& betas, const PrecomputeOptions& options) {
  require(!options.cache_dir.empty(), "cached avatar: no cache folder");
  require(betas.size() <= model.num_betas(), "cached avatar: ", betas.size(), " betas, the body model has ",
          model.num_betas());
  for (Eigen::Index i = 0; i < betas.size(); ++i)
    require(std::isfinite(betas[i]), "cached avatar: beta ", i, " is ", betas[i], ", expected a finite number");
  VecX b = VecX::Zero(model.num_betas());
  b.head(betas.size()) = betas;
  CachedAvatar out;
  out.path = (fs::path(options.cache_dir) / "avatars" / batch_avatar_file_name(avatar_content_key(model, b, options)))
                 .string();
  if (batch_output_done(out.path, body_model_hash(model), b)) return out;
  fs::create_directories(fs::path(out.path).parent_path());
  const Avatar a = precompute_avatar(model, b, options);
  const std::string temp = out.path + ".partial." + std::to_string(::getpid());
  try {
    write_avatar(a, temp);
    fs::rename(temp, out.path);
  } catch (...) {
    std::error_code ec;
    fs::remove(temp, ec);
    throw;
  }
  out.built = true;
  return out;
}

}  // namespace sflsh
