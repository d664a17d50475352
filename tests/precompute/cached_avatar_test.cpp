// cached_avatar: what `avatar: default` in a scene runs on. Built once per
// (model, betas, options) into the cache, found there afterwards, another
// file for another shape; bad betas refused before any work.
#include "sflsh/precompute/cached_avatar.hpp"

#include <gtest/gtest.h>

#include <filesystem>

#include "sflsh/asset/avatar_file.hpp"
#include "sflsh/body/body_model_io.hpp"
#include "test_support.hpp"

namespace sflsh {
namespace {

PrecomputeOptions coarse(const std::string& cache) {
  PrecomputeOptions o;  // the coarse mesh of the other precompute tests
  o.template_stage.mesh.cell_size = 0.08;
  o.template_stage.mesh.facet_size = 0.06;
  o.template_stage.mesh.facet_distance = 0.004;
  o.handles = 8;
  o.bbw.show_progress = false;
  o.cache_dir = cache;
  return o;
}

TEST(CachedAvatar, BuiltOnFirstUseFoundAfterwardsAndOneFilePerShape) {
  const test::TempDir dir;
  const BodyModel model = load_body_model("procedural");
  const PrecomputeOptions o = coarse(dir.file("cache"));
  VecX betas(2);
  betas << 1.5, -1.0;
  const CachedAvatar first = cached_avatar(model, betas, o);
  EXPECT_TRUE(first.built);
  ASSERT_TRUE(std::filesystem::exists(first.path)) << first.path;
  EXPECT_EQ(std::filesystem::path(first.path).parent_path(), std::filesystem::path(dir.file("cache")) / "avatars");
  const Avatar a = read_avatar(first.path);
  ASSERT_EQ(a.betas.size(), model.num_betas());  // padded with zeros
  EXPECT_EQ(a.betas[0], 1.5);
  EXPECT_EQ(a.betas[1], -1.0);
  EXPECT_EQ(a.betas.tail(model.num_betas() - 2).norm(), 0.0);
  EXPECT_EQ(a.num_handles(), 8);
  const auto written = std::filesystem::last_write_time(first.path);

  // The same shape again (given with its zeros): the same file, not rebuilt.
  VecX padded = VecX::Zero(model.num_betas());
  padded.head(2) = betas;
  const CachedAvatar again = cached_avatar(model, padded, o);
  EXPECT_FALSE(again.built);
  EXPECT_EQ(again.path, first.path);
  EXPECT_EQ(std::filesystem::last_write_time(first.path), written);
  // Another shape: another file. No partial file is left behind.
  const CachedAvatar zero = cached_avatar(model, VecX(), o);
  EXPECT_NE(zero.path, first.path);
  EXPECT_EQ(read_avatar(zero.path).betas.norm(), 0.0);
  for (const auto& e : std::filesystem::directory_iterator(dir.file("cache") + "/avatars"))
    EXPECT_EQ(e.path().extension(), ".h5") << e.path();
}

TEST(CachedAvatar, BadBetasOrNoCacheAreRefusedBeforeAnyWork) {
  const test::TempDir dir;
  const BodyModel model = load_body_model("procedural");
  const PrecomputeOptions o = coarse(dir.file("cache"));
  VecX nan(1);
  nan << std::nan("");
  test::expect_error([&] { cached_avatar(model, nan, o); }, {"beta 0", "finite"});
  test::expect_error([&] { cached_avatar(model, VecX::Zero(model.num_betas() + 1), o); },
                     {"11 betas", "has 10"});
  PrecomputeOptions none = o;
  none.cache_dir.clear();
  test::expect_error([&] { cached_avatar(model, VecX(), none); }, {"no cache folder"});
  EXPECT_FALSE(std::filesystem::exists(dir.file("cache")));
}

}  // namespace
}  // namespace sflsh
