#pragma once
// The viewer page's files, embedded into the binary at build time
// (cmake/embed_web_assets.cmake: apps/viewer/*.html, apps/viewer/src/*.js and
// three.js's module build from apps/viewer/node_modules, installed by
// scripts/setup.sh with `npm ci`), so `sflsh` serves the page with no files
// beside it and no network.
#include <string>
#include <string_view>

namespace sflsh::viewer {

struct WebAsset {
  std::string_view path;          ///< URL path, e.g. "/index.html"
  std::string_view content_type;  ///< e.g. "text/javascript; charset=utf-8"
  std::string_view body;
};

/// The asset served at `url_path` ("/" is "/index.html"; a query string is
/// ignored), or nullptr.
const WebAsset* find_web_asset(std::string_view url_path);

/// "" when the page is complete; otherwise a sentence saying what was not
/// embedded (three.js absent at build time) and how to fix it.
std::string web_assets_problem();

}  // namespace sflsh::viewer
