#include "sflsh/precompute/file_betas_avatar.hpp"

#include <algorithm>
#include <filesystem>
#include <iomanip>
#include <sstream>
#include <vector>

#include "sflsh/asset/avatar_file.hpp"
#include "sflsh/precompute/precompute.hpp"
#include "sflsh/body/body_model_io.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/fnv_hash.hpp"
#include "sflsh/core/progress.hpp"
#include "sflsh/core/timer.hpp"
#include "sflsh/io/crash_isolation.hpp"
#include "sflsh/io/hdf5_file.hpp"
#include "sflsh/volume/template_volume.hpp"

namespace sflsh {
namespace fs = std::filesystem;
namespace {

bool is_procedural(const std::string& source) { return source == "procedural" || source.rfind("procedural:", 0) == 0; }

/// The body model `base` was built from; throws if it is missing or changed.
BodyModel source_model(const Avatar& base, const std::string& base_path, std::string* used) {
  const std::string& src = base.model_source;
  require(!src.empty() && !base.model_hash.empty(), base_path,
          ": the avatar does not name its body model (/meta/model_source, /meta/model_hash are empty); "
          "--use-file-betas needs it to build the motion's shape");
  std::string spec = src;
  if (!is_procedural(src)) {
    const fs::path p(src);
    std::error_code ec;
    if (!fs::exists(p, ec) && p.is_relative()) {
      const fs::path beside = fs::path(base_path).parent_path() / p;
      if (fs::exists(beside, ec)) spec = beside.string();
    }
    if (!fs::exists(spec, ec))
      fail(base_path, ": built from body model '", src, "', which cannot be found",
           p.is_relative() ? " (looked in the current folder and next to the avatar)" : "",
           "; --use-file-betas needs that model file to build the motion's shape");
  }
  BodyModel model;
  try {
    model = load_body_model(spec);
  } catch (const Error& e) {
    fail(base_path, ": cannot load its body model '", spec, "': ", e.what());
  }
  const std::string hash = body_model_hash(model);
  if (hash != base.model_hash)
    fail(base_path, ": built from body model '", src, "' with hash ", base.model_hash, ", but '", spec,
         "' now has hash ", hash, "; --use-file-betas needs the same model (rebuild the avatar with `sflsh precompute "
         "--model ", src, "` or restore the model file)");
  *used = spec;
  return model;
}

/// A template-stage cache entry of `model_hash` whose tets are `elements`, or "".
std::string matching_template(const std::string& cache_dir, const std::string& model_hash, const Tets& elements) {
  std::error_code ec;
  if (cache_dir.empty() || !fs::is_directory(cache_dir, ec)) return "";
  std::vector<std::string> entries;
  for (const auto& e : fs::directory_iterator(cache_dir, ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind("template-", 0) == 0 && e.path().extension() == ".h5") entries.push_back(e.path().string());
  }
  std::sort(entries.begin(), entries.end());
  for (const std::string& path : entries) {
    auto matches = [&] {
      const io::Hdf5File f(path, io::Hdf5File::Mode::Read);
      if (!f.has("/template/format_version") || !f.has("/template/model_hash") || !f.has("/template/tet/elements"))
        return false;
      if (f.read_scalar("/template/format_version") != kTemplateVolumeFormatVersion) return false;
      if (f.read_string("/template/model_hash") != model_hash) return false;
      const auto shape = f.shape("/template/tet/elements");
      if (shape.size() != 2 || shape[0] != elements.rows() || shape[1] != 4) return false;
      const auto tets = f.read_int_matrix("/template/tet/elements", elements.rows(), 4);
      return std::equal(tets.data(), tets.data() + tets.size(), elements.data());
    };
    try {
      if (io::read_in_child_first(path, matches)) return path;  // an entry that crashes libhdf5 is skipped
    } catch (const Error&) {
      // An unreadable or damaged entry is not a match.
    }
  }
  return "";
}

std::string shaped_key(const Avatar& base, const VecX& betas) {
  Fnv1a64 f;
  std::ostringstream text;
  text << std::setprecision(17) << "avatar|" << kAvatarFormatVersion << '|' << base.model_hash << '|'
       << base.num_handles() << '|';
  for (Eigen::Index i = 0; i < betas.size(); ++i) text << betas[i] << ',';
  f.add(text.str());
  f.add(base.tet.elements.data(), sizeof(int) * std::size_t(base.tet.elements.size()));
  return f.hex();
}

/// Reads the cached avatar at `path` into *out when it is the one asked for.
bool read_cached(const std::string& path, const Avatar& base, const VecX& betas, Avatar* out) {
  std::error_code ec;
  if (!fs::exists(path, ec)) return false;
  try {
    Avatar a = read_avatar(path);
    if (a.model_hash != base.model_hash || a.num_handles() != base.num_handles() || a.betas.size() != betas.size() ||
        (a.betas - betas).cwiseAbs().maxCoeff() > 0)
      return false;
    *out = std::move(a);
    return true;
  } catch (const Error& e) {
    log_info(std::string("use-file-betas: ignoring unreadable cache entry (") + e.what() + "); rebuilding");
    return false;
  }
}

std::string list(const VecX& v) {
  std::ostringstream o;
  o << std::setprecision(4);
  for (Eigen::Index i = 0; i < v.size(); ++i) o << (i ? "," : "") << v[i];
  return o.str();
}

}  // namespace

VecX fit_betas(const VecX& betas, int model_betas, std::string* note) {
  require(model_betas >= 0, "fit_betas: negative model size ", model_betas);
  VecX out = VecX::Zero(model_betas);
  const Eigen::Index n = std::min<Eigen::Index>(betas.size(), model_betas);
  out.head(n) = betas.head(n);
  if (note) {
    std::ostringstream o;
    if (betas.size() > model_betas)
      o << "truncated from " << betas.size() << " to the model's " << model_betas << " shape directions";
    else if (betas.size() < model_betas)
      o << "zero-padded from " << betas.size() << " to the model's " << model_betas << " shape directions";
    *note = o.str();
  }
  return out;
}

Avatar avatar_for_file_betas(const Avatar& base, const std::string& base_path, const VecX& betas,
                             const std::string& cache_dir, FileBetasReport* report) {
  FileBetasReport local;
  FileBetasReport& r = report ? *report : local;
  r = FileBetasReport{};
  Timer timer;
  require(betas.allFinite(), "--use-file-betas: the motion's betas are not all finite");
  require(!cache_dir.empty(), "--use-file-betas needs a cache folder for the shaped avatar");
  require(base.num_handles() >= 1, base_path, ": the avatar has no handles");
  const BodyModel model = source_model(base, base_path, &r.model_source);
  r.file_betas = int(betas.size());
  r.model_betas = model.num_betas();
  r.betas = fit_betas(betas, model.num_betas(), &r.betas_note);
  r.handles = base.num_handles();
  r.avatar_path = (fs::path(cache_dir) / ("avatar-" + shaped_key(base, r.betas) + ".h5")).string();

  Avatar shaped;
  if (read_cached(r.avatar_path, base, r.betas, &shaped)) {
    r.from_cache = true;
    r.seconds = timer.seconds();
    return shaped;
  }

  PrecomputeOptions o;
  o.handles = base.num_handles();
  o.cache_dir = cache_dir;
  PrecomputeReport pr;
  TemplateVolume tv;
  r.template_path = matching_template(cache_dir, base.model_hash, base.tet.elements);
  if (!r.template_path.empty()) {
    log_info("use-file-betas: template stage from cache " + r.template_path + " (the mesh of " + base_path + ")");
    tv = load_template_volume(r.template_path);
    r.template_from_cache = true;
  } else {
    tv = cached_template_volume(model, o, &pr);
    r.template_path = pr.template_cache_path;
    r.template_from_cache = pr.template_from_cache;
  }
  if (tv.tet.elements.rows() != base.tet.elements.rows() || tv.tet.elements != base.tet.elements) {
    std::ostringstream n;
    n << "no cached template stage has the tet mesh of " << base_path << " (" << base.tet.num_elements()
      << " tets; built with other mesh options?): the shaped avatar uses the default mesh options ("
      << tv.tet.num_elements() << " tets)";
    r.mesh_note = n.str();
  }
  shaped = precompute_shape(tv, model, r.betas, o, &pr);
  std::error_code ec;
  fs::create_directories(cache_dir, ec);
  if (ec) fail("cannot create cache folder ", cache_dir, ": ", ec.message());
  write_avatar(shaped, r.avatar_path);
  r.seconds = timer.seconds();
  return shaped;
}

std::string FileBetasReport::describe() const {
  std::ostringstream o;
  o << "use-file-betas: betas (" << model_betas << "): " << list(betas);
  if (!betas_note.empty()) o << " (the motion file has " << file_betas << "; " << betas_note << ")";
  o << "\nuse-file-betas: body model " << model_source << ", " << handles << " handles; avatar "
    << (from_cache ? "reused from cache " : "built and cached as ") << avatar_path;
  if (!from_cache)
    o << " (template stage " << (template_from_cache ? "from cache " : "built, cached as ") << template_path << ")";
  o << std::fixed << std::setprecision(2) << " in " << seconds << " s\n";
  if (!mesh_note.empty()) o << "use-file-betas: note: " << mesh_note << "\n";
  return o.str();
}

}  // namespace sflsh
