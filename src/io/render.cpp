#include "sflsh/io/render.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "sflsh/core/error.hpp"
#include "sflsh/io/bitmap_font.hpp"
#include "sflsh/io/surface_normals.hpp"

namespace sflsh::io {

namespace {

constexpr Rgb8 kTextColor = {40, 40, 40};

/// Orthographic camera: screen axes `right`, `up` and the direction towards
/// the viewer (larger p·toward = closer).
struct Camera {
  Vec3 right, up, toward;
};

Camera camera_for(View view) {
  const Vec3 up(0, 1, 0);
  Vec3 toward;
  switch (view) {
    case View::Front: toward = Vec3(0, 0, 1); break;
    case View::Back: toward = Vec3(0, 0, -1); break;
    case View::Left: toward = Vec3(1, 0, 0); break;
    case View::Right: toward = Vec3(-1, 0, 0); break;
  }
  // Looking along -toward with Y up: right = (-toward) x up.
  return {(-toward).cross(up), up, toward};
}

/// Extent of the projection of V onto the camera's screen axes.
struct Window {
  double u0 = std::numeric_limits<double>::infinity(), u1 = -std::numeric_limits<double>::infinity();
  double v0 = std::numeric_limits<double>::infinity(), v1 = -std::numeric_limits<double>::infinity();
  void add(const Points& V, const Camera& cam) {
    for (Eigen::Index i = 0; i < V.rows(); ++i) {
      const Vec3 p = V.row(i);
      const double u = p.dot(cam.right), v = p.dot(cam.up);
      u0 = std::min(u0, u), u1 = std::max(u1, u), v0 = std::min(v0, v), v1 = std::max(v1, v);
    }
  }
  /// Grows to hold `other`, but by at most `margin` beyond this window per side.
  void add_within(const Window& other, double margin) {
    if (other.u0 > other.u1) return;  // empty
    u0 = std::min(u0, std::max(other.u0, u0 - margin)), u1 = std::max(u1, std::min(other.u1, u1 + margin));
    v0 = std::min(v0, std::max(other.v0, v0 - margin)), v1 = std::max(v1, std::min(other.v1, v1 + margin));
  }
  // A flat or single-point mesh still gets a finite, non-zero window.
  double width() const { return std::max(u1 - u0, 1e-6); }
  double height() const { return std::max(v1 - v0, 1e-6); }
};

/// Supersampled float colour buffer with a z-buffer.
struct Canvas {
  int w, h;
  std::vector<float> rgb, depth;
  Canvas(int w_, int h_, Rgb8 bg) : w(w_), h(h_), rgb(size_t(w_) * size_t(h_) * 3), depth(size_t(w_) * size_t(h_)) {
    for (size_t i = 0; i < depth.size(); ++i) {
      for (int c = 0; c < 3; ++c) rgb[3 * i + size_t(c)] = float(bg[size_t(c)]) / 255.f;
      depth[i] = -std::numeric_limits<float>::infinity();
    }
  }
};

/// Screen placement of a view: pixel = (ox + s*u, oy - s*v) in canvas pixels;
/// only pixels in [x0, x1) × [y0, y1) are drawn.
struct Placement {
  double ox, oy, s;
  int x0 = 0, y0 = 0, x1 = std::numeric_limits<int>::max(), y1 = std::numeric_limits<int>::max();
};

/// Shades a point with unit normal n (world) and albedo c. Key light from the
/// upper left front, a weak fill from the right, ambient, and a rim term that
/// brightens grazing angles so the silhouette reads against the background.
Vec3 shade(Vec3 n, const Vec3& c, const Camera& cam) {
  double ndv = n.dot(cam.toward);
  if (ndv < 0) n = -n, ndv = -ndv;  // two-sided: open meshes show their inside lit too
  const Vec3 key = (-0.35 * cam.right + 0.55 * cam.up + 0.75 * cam.toward).normalized();
  const Vec3 fill = (0.6 * cam.right - 0.1 * cam.up + 0.5 * cam.toward).normalized();
  const double diffuse = std::max(0.0, n.dot(key)), fill_d = std::max(0.0, n.dot(fill));
  const double rim = std::pow(1.0 - ndv, 3.0);
  const Vec3 out = c * (0.25 + 0.68 * diffuse + 0.18 * fill_d) + Vec3::Constant(0.22 * rim);
  return out.cwiseMin(1.0).cwiseMax(0.0);
}

/// z-buffered rasterization of every triangle, normals and colours
/// interpolated with the barycentric coordinates (exact for orthographic
/// projection, no perspective correction needed).
void draw_mesh(Canvas& canvas, const Points& V, const Triangles& F, const Points& colors, const Camera& cam,
               const Placement& at) {
  const Points N = vertex_normals(V, F);
  const Eigen::Index nv = V.rows();
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> S(nv, 3);  // x, y, depth
  for (Eigen::Index i = 0; i < nv; ++i) {
    const Vec3 p = V.row(i);
    S.row(i) << at.ox + at.s * p.dot(cam.right), at.oy - at.s * p.dot(cam.up), p.dot(cam.toward);
  }
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const int i0 = F(f, 0), i1 = F(f, 1), i2 = F(f, 2);
    const double x0 = S(i0, 0), y0 = S(i0, 1), x1 = S(i1, 0), y1 = S(i1, 1), x2 = S(i2, 0), y2 = S(i2, 1);
    const double area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0);
    if (std::abs(area) < 1e-12) continue;
    // Clamped in double first (a huge patch's corners lie far outside int range);
    // a triangle outside the clip rectangle gets an empty range.
    const auto clamp = [](double x, int lo, int hi) { return int(std::clamp(x, double(lo), double(hi))); };
    const int xa = clamp(std::floor(std::min({x0, x1, x2})), std::max(0, at.x0), std::min(canvas.w, at.x1));
    const int xb = clamp(std::ceil(std::max({x0, x1, x2})), std::max(0, at.x0) - 1, std::min(canvas.w, at.x1) - 1);
    const int ya = clamp(std::floor(std::min({y0, y1, y2})), std::max(0, at.y0), std::min(canvas.h, at.y1));
    const int yb = clamp(std::ceil(std::max({y0, y1, y2})), std::max(0, at.y0) - 1, std::min(canvas.h, at.y1) - 1);
    const double inv = 1.0 / area;
    for (int y = ya; y <= yb; ++y) {
      const double py = y + 0.5;
      for (int x = xa; x <= xb; ++x) {
        const double px = x + 0.5;
        // Barycentrics from edge functions; dividing by the signed area makes
        // the inside test independent of the triangle's screen winding.
        const double b0 = ((x2 - x1) * (py - y1) - (y2 - y1) * (px - x1)) * inv;
        const double b1 = ((x0 - x2) * (py - y2) - (y0 - y2) * (px - x2)) * inv;
        const double b2 = 1.0 - b0 - b1;
        if (b0 < 0 || b1 < 0 || b2 < 0) continue;
        const float d = float(b0 * S(i0, 2) + b1 * S(i1, 2) + b2 * S(i2, 2));
        const size_t k = size_t(y) * size_t(canvas.w) + size_t(x);
        if (d <= canvas.depth[k]) continue;
        canvas.depth[k] = d;
        Vec3 n = b0 * N.row(i0) + b1 * N.row(i1) + b2 * N.row(i2);
        const double len = n.norm();
        n = len > 0 ? Vec3(n / len) : cam.toward;
        const Vec3 c = b0 * colors.row(i0) + b1 * colors.row(i1) + b2 * colors.row(i2);
        const Vec3 out = shade(n, c, cam);
        for (int ch = 0; ch < 3; ++ch) canvas.rgb[3 * k + size_t(ch)] = float(out[ch]);
      }
    }
  }
}

/// Box-filters the supersampled canvas down by `ss` per axis.
Image downsample(const Canvas& canvas, int ss) {
  Image img(canvas.w / ss, canvas.h / ss);
  const float norm = 255.f / float(ss * ss);
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      float acc[3] = {0, 0, 0};
      for (int sy = 0; sy < ss; ++sy)
        for (int sx = 0; sx < ss; ++sx) {
          const size_t k = (size_t(y * ss + sy) * size_t(canvas.w) + size_t(x * ss + sx)) * 3;
          for (int c = 0; c < 3; ++c) acc[c] += canvas.rgb[k + size_t(c)];
        }
      for (int c = 0; c < 3; ++c) img.at(x, y)[c] = std::uint8_t(std::lround(std::clamp(acc[c] * norm, 0.f, 255.f)));
    }
  return img;
}

void check_surface_arrays(const Points& V, const Triangles& F, const char* what) {
  require(V.rows() > 0 && F.rows() > 0, what, ": nothing to render (", V.rows(), " vertices, ", F.rows(), " faces)");
  require(V.allFinite(), what, ": vertex positions contain NaN or Inf");
  require(F.minCoeff() >= 0 && F.maxCoeff() < V.rows(), what, ": face indices must lie in [0, ", V.rows(), ")");
}

std::string format_value(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", x);
  return buf;
}

/// Label size: 7-pixel glyphs scaled so text stays readable at any height.
int text_scale_for(int height) { return std::max(1, height / 240); }

}  // namespace

std::string view_name(View view) {
  switch (view) {
    case View::Front: return "front";
    case View::Back: return "back";
    case View::Left: return "left side";
    case View::Right: return "right side";
  }
  return "?";
}

Vec3 default_skin_color() { return Vec3(0.87, 0.70, 0.60); }

Image render_views(const Points& V, const Triangles& F, const RenderOptions& options, const Points& colors) {
  check_surface_arrays(V, F, "render_views");
  require(!options.views.empty(), "render_views: no views requested");
  require(options.width >= 16 && options.height >= 16, "render_views: image size must be at least 16 x 16, got ",
          options.width, " x ", options.height);
  require(options.supersample >= 1 && options.supersample <= 8, "render_views: supersample must be in 1..8, got ",
          options.supersample);
  require(colors.rows() == 0 || colors.rows() == V.rows(), "render_views: colors has ", colors.rows(),
          " rows, expected #V = ", V.rows());
  const Points albedo = colors.rows() ? colors : Points(options.base_color.transpose().replicate(V.rows(), 1));

  const int W = options.width, H = options.height, ss = options.supersample, ts = text_scale_for(H);
  const int pad = std::max(4, H / 30);
  const int top = options.title.empty() ? pad : pad + text_height(ts) + pad;
  const int bottom = options.captions ? pad + text_height(ts) + pad : pad;
  const int n = int(options.views.size());

  std::vector<Camera> cams;
  std::vector<Window> wins;
  double sum_width = 0, max_height = 0;
  for (View v : options.views) {
    cams.push_back(camera_for(v));
    Window w;
    w.add(V, cams.back());
    sum_width += w.width();
    max_height = std::max(max_height, w.height());
    wins.push_back(w);
  }
  // One scale for all panels so that front and side are comparable.
  const double avail_w = W - pad * (n + 1), avail_h = H - top - bottom;
  require(avail_w > 0 && avail_h > 0, "render_views: image ", W, " x ", H, " is too small for ", n, " views");
  const double s = std::min(avail_w / sum_width, avail_h / max_height);
  double x = 0.5 * (W - (s * sum_width + pad * (n - 1)));
  const double y_mid = top + 0.5 * avail_h;

  Canvas canvas(W * ss, H * ss, options.background);
  std::vector<double> centers;
  for (int i = 0; i < n; ++i) {
    const Window& w = wins[size_t(i)];
    const double ox = x - s * w.u0, oy = y_mid + s * 0.5 * (w.v0 + w.v1);
    draw_mesh(canvas, V, F, albedo, cams[size_t(i)], {ox * ss, oy * ss, s * ss});
    centers.push_back(x + 0.5 * s * w.width());
    x += s * w.width() + pad;
  }
  Image img = downsample(canvas, ss);
  if (options.captions)
    for (int i = 0; i < n; ++i) {
      const std::string cap = view_name(options.views[size_t(i)]);
      draw_text(img, int(centers[size_t(i)]) - text_width(cap, ts) / 2, H - bottom + pad, cap, kTextColor, ts);
    }
  if (!options.title.empty()) draw_text(img, pad, pad, options.title, kTextColor, ts);
  return img;
}

Image render_strip(const std::vector<StripFrame>& frames, const Triangles& F, const StripOptions& options) {
  require(!frames.empty(), "render_strip: no frames");
  require(options.height >= 64, "render_strip: height must be at least 64 pixels, got ", options.height);
  require(options.supersample >= 1 && options.supersample <= 8, "render_strip: supersample must be in 1..8, got ",
          options.supersample);
  require(std::isfinite(options.solid_margin) && options.solid_margin >= 0,
          "render_strip: solid_margin must be finite and >= 0, got ", options.solid_margin);
  const Camera cam = camera_for(options.view);
  Window win, solid_win;
  double vmin = std::numeric_limits<double>::infinity(), vmax = -vmin;
  for (size_t i = 0; i < frames.size(); ++i) {
    const StripFrame& fr = frames[i];
    check_surface_arrays(fr.vertices, F, "render_strip");
    require(fr.values.size() == fr.vertices.rows(), "render_strip: frame ", i, " has ", fr.values.size(),
            " values, expected one per vertex (", fr.vertices.rows(), ")");
    require(fr.values.allFinite(), "render_strip: frame ", i, " values contain NaN or Inf");
    win.add(fr.vertices, cam);
    for (const SolidSurface& solid : fr.solids) {
      check_surface_arrays(solid.vertices, solid.faces, "render_strip (solid)");
      require(solid.color.allFinite(), "render_strip: frame ", i, " has a solid with a non-finite colour");
      if (solid.frames_view) solid_win.add(solid.vertices, cam);
    }
    vmin = std::min(vmin, fr.values.minCoeff());
    vmax = std::max(vmax, fr.values.maxCoeff());
  }
  win.add_within(solid_win, options.solid_margin * std::max(win.width(), win.height()));
  if (std::isfinite(options.value_min)) vmin = options.value_min;
  if (std::isfinite(options.value_max)) vmax = options.value_max;

  const int H = options.height, ss = options.supersample, ts = text_scale_for(H);
  const int pad = std::max(4, H / 30), gap = pad / 2;
  const bool has_captions = std::any_of(frames.begin(), frames.end(), [](const auto& f) { return !f.label.empty(); });
  const bool has_header = !options.title.empty() || !options.value_label.empty();
  const int top = has_header ? pad + text_height(ts) + pad : pad;
  const int bottom = has_captions ? pad + text_height(ts) + pad : pad;
  const double s = double(H - top - bottom) / win.height();
  const int panel_w = std::max(int(std::ceil(s * win.width())), 8);
  const int n = int(frames.size());

  // Colour bar to the right of the frames: bar, then min / mid / max labels.
  const std::string lo = format_value(vmin), hi = format_value(vmax), mid = format_value(0.5 * (vmin + vmax));
  const int bar_w = std::max(10, H / 24);
  const int label_w = std::max({text_width(lo, ts), text_width(hi, ts), text_width(mid, ts)});
  const int bar_region = std::max(pad + bar_w + pad + label_w + pad, text_width(options.value_label, ts) + 2 * pad);
  const int frames_w = pad + n * panel_w + (n - 1) * gap;
  const int W = frames_w + bar_region;
  const int title_w = text_width(options.title, ts) + 2 * pad;
  const int W_total = std::max(W, title_w + bar_region);

  Canvas canvas(W_total * ss, H * ss, options.background);
  const double oy = top + s * win.v1;
  for (int i = 0; i < n; ++i) {
    const StripFrame& fr = frames[size_t(i)];
    const int px = pad + i * (panel_w + gap);
    const double ox = px - s * win.u0;
    const Placement at{ox * ss, oy * ss, s * ss, px * ss, top * ss, (px + panel_w) * ss, (H - bottom) * ss};
    draw_mesh(canvas, fr.vertices, F, colormap_colors(options.colormap, fr.values, vmin, vmax), cam, at);
    for (const SolidSurface& solid : fr.solids)
      draw_mesh(canvas, solid.vertices, solid.faces, solid.color.transpose().replicate(solid.vertices.rows(), 1), cam, at);
  }
  Image img = downsample(canvas, ss);

  for (int i = 0; i < n; ++i) {
    const std::string& cap = frames[size_t(i)].label;
    const int cx = pad + i * (panel_w + gap) + panel_w / 2;
    draw_text(img, cx - text_width(cap, ts) / 2, H - bottom + pad, cap, kTextColor, ts);
  }
  const int bx = W_total - bar_region + pad, by0 = top, by1 = H - bottom;
  img.fill_rect(bx - 1, by0 - 1, bx + bar_w + 1, by1 + 1, {90, 90, 90});
  for (int y = by0; y < by1; ++y) {
    const double t = 1.0 - (y + 0.5 - by0) / double(by1 - by0);  // top = max
    const Vec3 c = colormap_rgb(options.colormap, t);
    img.fill_rect(bx, y, bx + bar_w, y + 1,
                  {std::uint8_t(std::lround(255 * c[0])), std::uint8_t(std::lround(255 * c[1])),
                   std::uint8_t(std::lround(255 * c[2]))});
  }
  const int lx = bx + bar_w + pad;
  draw_text(img, lx, by0, hi, kTextColor, ts);
  draw_text(img, lx, (by0 + by1 - text_height(ts)) / 2, mid, kTextColor, ts);
  draw_text(img, lx, by1 - text_height(ts), lo, kTextColor, ts);
  if (!options.value_label.empty())
    draw_text(img, W_total - bar_region + pad, pad, options.value_label, kTextColor, ts);
  if (!options.title.empty()) draw_text(img, pad, pad, options.title, kTextColor, ts);
  return img;
}

}  // namespace sflsh::io
