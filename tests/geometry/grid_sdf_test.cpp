// The grid SDF's interpolant (node values, linear precision, C¹ across
// cells, derivatives against finite differences) and its file (round trip,
// one clear error per kind of bad file).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "sdf_checks.hpp"
#include "sflsh/geometry/grid_sdf.hpp"
#include "sflsh/geometry/primitive_sdfs.hpp"
#include "sflsh/io/hdf5_file.hpp"
#include "test_support.hpp"

namespace sflsh {
namespace {

using geometry::GridSdf;

/// `f` sampled on a grid of `n` nodes per axis over [lo, lo + (n−1)h]³.
GridSdf sample_grid(const geometry::Sdf& f, const Vec3& lo, double h, int n) {
  std::vector<double> v;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) v.push_back(f.distance(lo + h * Vec3(i, j, k)));
  return GridSdf(lo, h, Eigen::Vector3i::Constant(n), v);
}

/// Random points in [lo, hi]; with h > 0, moved off the cell faces of a grid
/// of spacing h through the origin (the interpolant's Hessian jumps there, so
/// central differences of the gradient must not straddle a face).
std::vector<Vec3> random_points(const Vec3& lo, const Vec3& hi, int n, unsigned seed, double h = 0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Vec3> out;
  for (int i = 0; i < n; ++i) {
    Vec3 x = lo + Vec3(u(rng), u(rng), u(rng)).cwiseProduct(hi - lo);
    for (int a = 0; h > 0 && a < 3; ++a) {
      const double frac = x[a] / h - std::floor(x[a] / h);
      if (frac < 1e-3 || frac > 1 - 1e-3) x[a] += 0.01 * h;
    }
    out.push_back(x);
  }
  return out;
}

TEST(GridSdf, InterpolatesNodeValuesAndReproducesLinearFieldsExactly) {
  const geometry::PlaneSdf plane(Vec3(0.3, -0.5, 0.8), 0.05);
  const GridSdf g = sample_grid(plane, Vec3(-0.1, -0.1, -0.1), 0.02, 6);
  for (int i = 0; i < 6; ++i) EXPECT_DOUBLE_EQ(g.evaluate(g.node_position(i, 5 - i, 2)).distance, g.node_value(i, 5 - i, 2));
  // Everywhere in the box, boundary cells included (ghost nodes are linear).
  for (const Vec3& x : random_points(Vec3::Constant(-0.1), Vec3::Constant(0.0), 100, 1)) {
    const auto s = g.evaluate(x, true);
    EXPECT_NEAR(s.distance, plane.distance(x), 1e-14);
    EXPECT_LT((s.gradient - plane.normal()).norm(), 1e-12);
    EXPECT_LT(s.hessian.norm(), 1e-9);
  }
}

TEST(GridSdf, ApproximatesASphereAndItsDerivativesMatchFiniteDifferences) {
  const geometry::SphereSdf sphere(0.1);
  const double h = 0.01;
  const GridSdf g = sample_grid(sphere, Vec3::Constant(-0.15), h, 31);
  double worst = 0;
  for (const Vec3& x : random_points(Vec3::Constant(-0.14), Vec3::Constant(0.14), 300, 2, h)) {
    if (x.norm() < 0.03) continue;  // the sphere's centre is a kink
    worst = std::max(worst, std::abs(g.distance(x) - sphere.distance(x)));
    test::expect_derivatives_match_fd(g, x, 1e-6, 1e-4);
  }
  // Cubic interpolation of a smooth field: error ~ h²·curvature, far below a voxel.
  EXPECT_LT(worst, 0.02 * h);
  // Outside the grid box (the continuous extension) the derivatives are consistent too.
  for (const Vec3& x : {Vec3(0.2, 0.013, 0.027), Vec3(0.2, -0.19, 0.004), Vec3(0.18, 0.2, -0.21)})
    test::expect_derivatives_match_fd(g, x, 1e-6, 1e-4);
  EXPECT_NEAR(g.distance(Vec3(0.25, 0, 0)), g.distance(Vec3(0.15, 0, 0)) + 0.1, 1e-12);
}

TEST(GridSdf, GradientIsContinuousAcrossCellFaces) {
  // A box field has kinks, so the node values are far from smooth: the
  // interpolant must still be C¹ at every cell boundary.
  const geometry::BoxSdf box(Vec3(0.05, 0.07, 0.03));
  const double h = 0.01;
  const GridSdf g = sample_grid(box, Vec3::Constant(-0.1), h, 21);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.09, 0.09);
  for (int trial = 0; trial < 200; ++trial) {
    Vec3 x(u(rng), u(rng), u(rng));
    const int axis = trial % 3;
    x[axis] = -0.1 + h * std::round((x[axis] + 0.1) / h);  // on a cell face
    const Vec3 d = 1e-9 * Vec3::Unit(axis);
    const auto a = g.evaluate(x - d), b = g.evaluate(x + d);
    EXPECT_NEAR(a.distance, b.distance, 1e-8);  // |∇φ|·2e-9 apart
    EXPECT_LT((a.gradient - b.gradient).norm(), 1e-5) << x.transpose();
  }
}

TEST(GridSdf, FileRoundTripIsExact) {
  test::TempDir dir;
  const GridSdf g = sample_grid(geometry::SphereSdf(0.05), Vec3(0.1, -0.2, 0.3), 0.013, 7);
  geometry::write_grid_sdf(g, dir.file("g.h5"));
  const GridSdf r = geometry::read_grid_sdf(dir.file("g.h5"));
  EXPECT_EQ(r.dims(), g.dims());
  EXPECT_EQ(r.origin(), g.origin());
  EXPECT_EQ(r.spacing(), g.spacing());
  EXPECT_EQ(r.values(), g.values());
}

/// Writes a grid file by hand with the given dims dataset and values.
void write_raw(const std::string& path, const Eigen::Vector3i& dims, const std::vector<double>& values,
               const std::vector<std::int64_t>& shape) {
  io::Hdf5File f(path, io::Hdf5File::Mode::Write);
  f.write_string("/meta/format", "sflsh grid sdf");
  f.write_scalar("/meta/version", std::int64_t(1));
  f.write_matrix("/sdf/origin", Vec3::Zero().transpose());
  f.write_scalar("/sdf/spacing", 0.01);
  f.write_matrix("/sdf/dims", dims.transpose());
  f.write_nd("/sdf/values", values.data(), shape);
  f.commit();
}

TEST(GridSdf, BadFilesGiveOneClearError) {
  test::TempDir dir;
  std::vector<double> v(24, 0.5);
  // NaN value.
  std::vector<double> nan_values = v;
  nan_values[5] = std::nan("");
  write_raw(dir.file("nan.h5"), Eigen::Vector3i(2, 3, 4), nan_values, {4, 3, 2});
  test::expect_error([&] { geometry::read_grid_sdf(dir.file("nan.h5")); }, {"nan.h5", "/sdf/values"});
  // Dims that do not match the values' shape.
  write_raw(dir.file("dims.h5"), Eigen::Vector3i(2, 2, 6), v, {4, 3, 2});
  test::expect_error([&] { geometry::read_grid_sdf(dir.file("dims.h5")); }, {"dims.h5", "/sdf/values", "shape"});
  // Too few nodes.
  write_raw(dir.file("one.h5"), Eigen::Vector3i(1, 4, 6), v, {6, 4, 1});
  test::expect_error([&] { geometry::read_grid_sdf(dir.file("one.h5")); }, {"one.h5", "/sdf/dims", ">= 2"});
  // Truncated.
  const GridSdf g = sample_grid(geometry::SphereSdf(0.05), Vec3::Zero(), 0.01, 12);
  geometry::write_grid_sdf(g, dir.file("t.h5"));
  std::filesystem::resize_file(dir.file("t.h5"), std::filesystem::file_size(dir.file("t.h5")) / 2);
  test::expect_error([&] { geometry::read_grid_sdf(dir.file("t.h5")); }, {"t.h5"});
  // Missing, and not a grid SDF.
  test::expect_error([&] { geometry::read_grid_sdf(dir.file("none.h5")); }, {"none.h5", "not found"});
  {
    io::Hdf5File f(dir.file("other.h5"), io::Hdf5File::Mode::Write);
    f.write_scalar("/x", 1.0);
    f.commit();
  }
  test::expect_error([&] { geometry::read_grid_sdf(dir.file("other.h5")); }, {"other.h5", "/meta/format"});
  // The constructor checks too.
  test::expect_error([&] { GridSdf(Vec3::Zero(), -1.0, Eigen::Vector3i(2, 2, 2), std::vector<double>(8)); },
                     {"spacing"});
}

}  // namespace
}  // namespace sflsh
