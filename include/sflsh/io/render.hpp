#pragma once
// A small software rasterizer for pictures of bodies that need no display:
// orthographic views, auto-framed, z-buffered, Lambert + ambient + a soft rim
// light, per-vertex colours interpolated, supersampled for anti-aliasing.
// Y is up (sflsh convention); the body faces +Z.
#include <limits>
#include <string>
#include <vector>

#include "sflsh/core/types.hpp"
#include "sflsh/io/colormap.hpp"
#include "sflsh/io/png_image.hpp"

namespace sflsh::io {

/// Where the orthographic camera looks from (all views keep Y up).
enum class View {
  Front,  ///< from +Z: the body's left is on the image's right
  Back,   ///< from -Z
  Left,   ///< from +X (the body's left side; its front faces image-left)
  Right,  ///< from -X
};

/// Caption used for a view ("front", "back", "left side", "right side").
std::string view_name(View view);

/// Default surface colour (a light skin tone, RGB in [0, 1]).
Vec3 default_skin_color();

struct RenderOptions {
  int width = 800;                                ///< output width in pixels
  int height = 800;                               ///< output height in pixels
  std::vector<View> views = {View::Front, View::Left};  ///< panels, left to right
  int supersample = 2;                            ///< samples per pixel per axis (1 = none)
  Rgb8 background = {232, 232, 232};              ///< light grey
  Vec3 base_color = default_skin_color();         ///< used where no per-vertex colours are given
  bool captions = true;                           ///< view names under the panels
  std::string title;                              ///< optional line at the top
};

/// Renders the surface (V: #V by 3 metres, F: #F by 3) side by side from each
/// of `options.views`, all at the same scale, framed to fill the image.
/// `colors` is empty or #V by 3 RGB in [0, 1].
Image render_views(const Points& V, const Triangles& F, const RenderOptions& options = {},
                   const Points& colors = Points());

/// A surface drawn in one colour next to a strip frame's coloured surface
/// (e.g. a rigid object of a scene in neutral grey).
struct SolidSurface {
  Points vertices;                    ///< #N by 3 (m, same space as the frame's vertices)
  Triangles faces;                    ///< #M by 3
  Vec3 color = Vec3(0.6, 0.6, 0.6);   ///< albedo, RGB in [0, 1] (default neutral grey)
  /// Counts towards the strip's framing (within StripOptions::solid_margin);
  /// false for unbounded things drawn as big patches, such as a floor.
  bool frames_view = true;
};

/// One frame of a strip: the surface and a scalar per vertex (e.g. soft-tissue
/// displacement magnitude in mm).
struct StripFrame {
  Points vertices;    ///< #V by 3
  VecX values;        ///< #V
  std::string label;  ///< caption under the frame (e.g. "t=0.50 s"), may be empty
  /// Drawn with the surface (z-buffered together), clipped to the frame's panel.
  std::vector<SolidSurface> solids;
};

struct StripOptions {
  int height = 480;                  ///< image height in pixels; width follows the frames
  View view = View::Front;
  Colormap colormap = Colormap::Turbo;
  /// Value range mapped to the colormap; NaN = min / max over all frames.
  double value_min = std::numeric_limits<double>::quiet_NaN();
  double value_max = std::numeric_limits<double>::quiet_NaN();
  std::string value_label;           ///< colour-bar title (e.g. "displacement mm")
  std::string title;                 ///< optional line at the top
  int supersample = 2;
  Rgb8 background = {232, 232, 232};
  /// How far solids (SolidSurface::frames_view) may widen the window beyond
  /// the coloured surfaces' own, per side, as a fraction of that window's
  /// larger side (default 0.5); what lies further out is clipped.
  double solid_margin = 0.5;
};

/// Renders frames side by side with one shared world window (so motion shows
/// as movement between panels) and a colour bar with min / max labels on the
/// right. The window holds every frame's coloured surface and, within
/// `solid_margin`, its solids; each panel clips what falls outside it. All
/// frames share the faces F (#F by 3). Throws on an empty list or mismatched
/// sizes.
Image render_strip(const std::vector<StripFrame>& frames, const Triangles& F, const StripOptions& options = {});

}  // namespace sflsh::io
