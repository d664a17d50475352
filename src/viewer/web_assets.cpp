#include "sflsh/viewer/web_assets.hpp"

namespace sflsh::viewer {
namespace detail {
// Defined in the generated viewer_web_assets.cpp (cmake/embed_web_assets.cmake).
extern const WebAsset kAssets[];
extern const int kNumAssets;
extern const char kMissing[];
}  // namespace detail

const WebAsset* find_web_asset(std::string_view url_path) {
  const std::size_t query = url_path.find_first_of("?#");
  if (query != std::string_view::npos) url_path = url_path.substr(0, query);
  if (url_path == "/") url_path = "/index.html";
  for (int i = 0; i < detail::kNumAssets; ++i)
    if (detail::kAssets[i].path == url_path) return &detail::kAssets[i];
  return nullptr;
}

std::string web_assets_problem() { return detail::kMissing; }

}  // namespace sflsh::viewer
