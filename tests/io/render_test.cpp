#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "sflsh/core/error.hpp"
#include "sflsh/io/bitmap_font.hpp"
#include "sflsh/io/colormap.hpp"
#include "sflsh/io/png_image.hpp"
#include "sflsh/io/render.hpp"
#include "test_support.hpp"

namespace sflsh::io {
namespace {

/// Unit sphere (radius r, centre c) by subdividing an octahedron `levels`
/// times and projecting; faces counter-clockwise from outside.
void sphere(int levels, double r, const Vec3& c, Points& V, Triangles& F) {
  std::vector<Vec3> verts = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  std::vector<std::array<int, 3>> faces = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                                           {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      verts.push_back((verts[size_t(a)] + verts[size_t(b)]).normalized());
      return mid[key] = int(verts.size()) - 1;
    };
    std::vector<std::array<int, 3>> next;
    for (auto [a, b, cc] : faces) {
      const int ab = midpoint(a, b), bc = midpoint(b, cc), ca = midpoint(cc, a);
      next.push_back({a, ab, ca});
      next.push_back({ab, b, bc});
      next.push_back({ca, bc, cc});
      next.push_back({ab, bc, ca});
    }
    faces = next;
  }
  V.resize(Eigen::Index(verts.size()), 3);
  for (size_t i = 0; i < verts.size(); ++i) V.row(Eigen::Index(i)) = (c + r * verts[i].normalized()).transpose();
  F.resize(Eigen::Index(faces.size()), 3);
  for (size_t i = 0; i < faces.size(); ++i) F.row(Eigen::Index(i)) << faces[i][0], faces[i][1], faces[i][2];
}

bool is_background(const Image& img, int x, int y, Rgb8 bg) { return img.pixel(x, y) == bg; }
int luminance(Rgb8 c) { return int(c[0]) + int(c[1]) + int(c[2]); }

TEST(Render, FrontAndSideFramedOnBackground) {
  Points V;
  Triangles F;
  sphere(3, 0.5, Vec3(0.2, 1.0, 0.0), V, F);
  RenderOptions opt;
  opt.width = 240;
  opt.height = 120;
  opt.captions = false;
  const Image img = render_views(V, F, opt);
  ASSERT_EQ(img.width, 240);
  ASSERT_EQ(img.height, 120);
  ASSERT_EQ(img.rgb.size(), size_t(240 * 120 * 3));
  for (auto [x, y] : {std::pair{0, 0}, {239, 0}, {0, 119}, {239, 119}, {120, 60}})
    EXPECT_TRUE(is_background(img, x, y, opt.background)) << x << "," << y;
  // Two equal spheres side by side: panel centres at 1/4 and 3/4 of the width.
  for (int x : {60, 180}) {
    EXPECT_FALSE(is_background(img, x, 60, opt.background)) << x;
    // Key light from the upper left: upper-left of the disc brighter than lower-right.
    EXPECT_GT(luminance(img.pixel(x - 25, 35)), luminance(img.pixel(x + 25, 85)) + 60) << x;
  }
}

TEST(Render, ZBufferShowsNearestSurfaceAndColorsInterpolate) {
  Points V;
  Triangles F;
  sphere(2, 0.5, Vec3(0, 0, 0), V, F);  // red, behind
  Points V2;
  Triangles F2;
  sphere(2, 0.25, Vec3(0, 0, 1.0), V2, F2);  // blue, in front (+Z faces the front camera)
  Points VA(V.rows() + V2.rows(), 3);
  VA << V, V2;
  Triangles FA(F.rows() + F2.rows(), 3);
  FA << F, (F2.array() + int(V.rows())).matrix();
  Points C(VA.rows(), 3);
  C.topRows(V.rows()).rowwise() = Eigen::RowVector3d(1, 0, 0);
  C.bottomRows(V2.rows()).rowwise() = Eigen::RowVector3d(0, 0, 1);
  RenderOptions opt;
  opt.width = opt.height = 100;
  opt.views = {View::Front};
  opt.captions = false;
  const Image front = render_views(VA, FA, opt, C);
  const Rgb8 centre = front.pixel(50, 50), ring = front.pixel(50, 18);
  EXPECT_GT(centre[2], 3 * centre[0]) << "the near blue sphere must hide the red one";
  EXPECT_GT(ring[0], 3 * ring[2]) << "outside the small sphere the red one shows";
  opt.views = {View::Back};
  const Image back = render_views(VA, FA, opt, C);
  EXPECT_GT(back.pixel(50, 50)[0], 3 * back.pixel(50, 50)[2]) << "from behind the red sphere hides the blue one";
}

TEST(Render, StripDimensionsColorsAndBar) {
  Points V;
  Triangles F;
  sphere(2, 0.3, Vec3(0, 1, 0), V, F);
  std::vector<StripFrame> frames;
  for (int i = 0; i < 3; ++i) {
    StripFrame fr;
    fr.vertices = V;
    fr.vertices.col(1).array() += 0.2 * i;  // rises: shared window shows it
    fr.values = VecX::Constant(V.rows(), double(i));  // 0, 1, 2 -> bottom, middle, top of the map
    fr.label = "t=" + std::to_string(i);
    frames.push_back(fr);
  }
  StripOptions opt;
  opt.height = 200;
  opt.value_label = "disp mm";
  const Image img = render_strip(frames, F, opt);
  EXPECT_EQ(img.height, 200);
  const Image one = render_strip({frames[0]}, F, opt);
  EXPECT_EQ(one.height, 200);
  EXPECT_GT(img.width, one.width + 100) << "each frame adds a panel";

  // Find the panels' sphere centres: scan the row through the first sphere's centre.
  auto dominant = [](Rgb8 c) { return c[0] > c[2] + 60 ? 'r' : (c[2] > c[0] + 60 ? 'b' : '?'); };
  int blue = 0, red = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const Rgb8 c = img.pixel(x, y);
      if (c == opt.background) continue;
      blue += dominant(c) == 'b';
      red += dominant(c) == 'r';
    }
  EXPECT_GT(blue, 300) << "frame 0 (value = min) is drawn in turbo's blue";
  EXPECT_GT(red, 300) << "frame 2 (value = max) is drawn in turbo's red";
  // The colour bar's top and bottom rows hold the map's end colours.
  const Vec3 top = colormap_rgb(Colormap::Turbo, 1.0), bot = colormap_rgb(Colormap::Turbo, 0.0);
  auto near = [](Rgb8 c, const Vec3& ref) {
    return std::abs(c[0] - 255 * ref[0]) < 12 && std::abs(c[1] - 255 * ref[1]) < 12 && std::abs(c[2] - 255 * ref[2]) < 12;
  };
  bool found_top = false, found_bot = false;
  for (int x = img.width - 80; x < img.width; ++x)
    for (int y = 0; y < img.height; ++y) {
      found_top |= y < img.height / 3 && near(img.pixel(x, y), top);
      found_bot |= y > 2 * img.height / 3 && near(img.pixel(x, y), bot);
    }
  EXPECT_TRUE(found_top && found_bot);
  frames[1].values.resize(3);
  EXPECT_THROW(render_strip(frames, F, opt), Error);
}

TEST(Render, StripSolidsWidenTheWindowOnlyWithinTheMargin) {
  // Body: a ball of diameter 1 at the origin; solids: a green ball of radius
  // 0.1 at x = 0.7 and a grey one at x = 3 (beyond the 0.5 m margin).
  StripFrame fr;
  Triangles F;
  sphere(3, 0.5, Vec3::Zero(), fr.vertices, F);
  fr.values = VecX::Zero(fr.vertices.rows());
  StripOptions opt;
  opt.height = 240;
  const Image bare = render_strip({fr}, F, opt);
  SolidSurface green, far;
  sphere(2, 0.1, Vec3(0.7, 0, 0), green.vertices, green.faces);
  green.color = Vec3(0.1, 0.8, 0.1);
  sphere(2, 0.1, Vec3(3.0, 0, 0), far.vertices, far.faces);
  fr.solids = {green, far};
  const Image with = render_strip({fr}, F, opt);
  // The body's diameter in pixels: the first run of non-background pixels
  // along the middle row (the window is centred vertically).
  const int y = opt.height / 2;
  int x0 = 0;
  while (x0 < bare.width && bare.pixel(x0, y) == opt.background) ++x0;
  int d = 0;
  while (x0 + d < bare.width && bare.pixel(x0 + d, y) != opt.background) ++d;
  ASSERT_GT(d, 100);
  // The window grew by half its size (0.5 m of a 1 m window), not to x = 3.1.
  EXPECT_NEAR(with.width - bare.width, 0.5 * d, 2.0);
  const Rgb8 g = with.pixel(x0 + int(1.2 * d), y);  // x = 0.7
  EXPECT_GT(int(g[1]), int(g[0]) + 60);
  // A solid that does not frame the view leaves the window alone.
  for (auto& s : fr.solids) s.frames_view = false;
  EXPECT_EQ(render_strip({fr}, F, opt).width, bare.width);
}

TEST(Colormap, KnownValues) {
  const Vec3 v0 = colormap_rgb(Colormap::Viridis, 0.0), v1 = colormap_rgb(Colormap::Viridis, 1.0);
  EXPECT_NEAR(v0[0] * 255, 68, 0.5);
  EXPECT_NEAR(v0[2] * 255, 84, 0.5);
  EXPECT_NEAR(v1[0] * 255, 253, 0.5);
  EXPECT_NEAR(v1[1] * 255, 231, 0.5);
  // viridis at 0.55 lies between the 0.5 and 0.6 stops.
  EXPECT_NEAR(colormap_rgb(Colormap::Viridis, 0.55)[1] * 255, (145 + 168) / 2.0, 0.5);
  const Vec3 t = colormap_rgb(Colormap::Turbo, 0.5);
  EXPECT_GT(t[1], t[0]);  // turbo's middle is green-yellow
  EXPECT_GT(t[1], t[2]);
  EXPECT_EQ(colormap_rgb(Colormap::Turbo, 7.0), colormap_rgb(Colormap::Turbo, 1.0));  // clamped
  EXPECT_THROW(colormap_from_name("jet"), Error);
}

TEST(PngImage, RoundTripIsLossless) {
  test::TempDir dir;
  Image img(17, 9, {10, 20, 30});
  img.set(3, 4, {255, 0, 128});
  img.fill_rect(10, 1, 12, 3, {1, 2, 3});
  draw_text(img, 0, 0, "7", {200, 200, 200});
  write_png(dir.file("a.png"), img);
  const Image back = read_png(dir.file("a.png"));
  EXPECT_EQ(back.width, 17);
  EXPECT_EQ(back.height, 9);
  EXPECT_EQ(back.rgb, img.rgb);
  EXPECT_THROW(read_png(dir.file("missing.png")), Error);
}

TEST(BitmapFont, InkMatchesGlyph) {
  Image img(20, 10, {0, 0, 0});
  draw_text(img, 1, 1, "1", {255, 255, 255});
  int ink = 0;
  for (size_t i = 0; i < img.rgb.size(); i += 3) ink += img.rgb[i] == 255;
  EXPECT_EQ(ink, 10);  // the "1" glyph has 10 dots
  EXPECT_EQ(text_width("12", 2), (2 * kGlyphAdvance - 1) * 2);
}

}  // namespace
}  // namespace sflsh::io
