#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <limits>

#include "sflsh/core/error.hpp"
#include "sflsh/io/hdf5_file.hpp"
#include "test_support.hpp"

using namespace sflsh;
using io::Hdf5File;

TEST(Hdf5File, RoundTripMatricesStringsScalars) {
  test::TempDir tmp;
  const std::string path = tmp.file("a.h5");
  MatXr m(3, 2);
  m << 1, 2, 3, 4, 5, 6.5;
  Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> im(2, 2);
  im << 1, -2, 3, 4;
  {
    Hdf5File f(path, Hdf5File::Mode::Write);
    f.write_matrix("/g/m", m);
    f.write_matrix("/g/h/i", im);
    f.write_strings("/names", {"pelvis", "left_hip"});
    f.write_scalar("/meta/v", std::int64_t(7));
    f.commit();
  }
  Hdf5File f(path, Hdf5File::Mode::Read);
  EXPECT_TRUE(f.has("/g/h/i"));
  EXPECT_FALSE(f.has("/g/x/y"));
  EXPECT_EQ((f.read_matrix("/g/m", 3, 2) - m).norm(), 0.0);
  EXPECT_EQ(f.read_int_matrix("/g/h/i", 2, 2), im);
  EXPECT_EQ(f.read_strings("/names")[1], "left_hip");
  EXPECT_EQ(f.read_scalar("/meta/v"), 7.0);
}

TEST(Hdf5File, ErrorsNameTheDatasetAndShape) {
  test::TempDir tmp;
  const std::string path = tmp.file("b.h5");
  MatXr m = MatXr::Ones(4, 3);
  m(2, 1) = std::numeric_limits<double>::quiet_NaN();
  {
    Hdf5File f(path, Hdf5File::Mode::Write);
    f.write_matrix("/x", MatXr::Ones(4, 3));
    f.write_matrix("/bad", m);
    f.commit();
  }
  Hdf5File f(path, Hdf5File::Mode::Read);
  try {
    f.read_matrix("/x", 4, 2);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/x has shape (4, 3), expected (4, 2)"), std::string::npos) << e.what();
  }
  try {
    f.read_matrix("/missing");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/missing is missing"), std::string::npos) << e.what();
  }
  try {
    f.read_matrix("/bad");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("non-finite"), std::string::npos) << e.what();
  }
}

TEST(Hdf5File, TruncatedAndMissingFilesAreErrors) {
  test::TempDir tmp;
  const std::string path = tmp.file("c.h5");
  {
    Hdf5File f(path, Hdf5File::Mode::Write);
    f.write_matrix("/x", MatXr::Random(200, 50));
    f.commit();
  }
  auto size = std::filesystem::file_size(path);
  std::filesystem::resize_file(path, size / 2);
  EXPECT_THROW(
      {
        Hdf5File f(path, Hdf5File::Mode::Read);
        f.read_matrix("/x");
      },
      Error);
  EXPECT_THROW(Hdf5File(tmp.file("nope.h5"), Hdf5File::Mode::Read), Error);
}

TEST(Hdf5File, UncommittedWriteLeavesNoFile) {
  test::TempDir tmp;
  const std::string path = tmp.file("d.h5");
  {
    Hdf5File f(path, Hdf5File::Mode::Write);
    f.write_matrix("/x", MatXr::Ones(2, 2));
  }
  EXPECT_FALSE(std::filesystem::exists(path));
  EXPECT_FALSE(std::filesystem::exists(path + ".partial"));
}

TEST(Hdf5File, AppendableDatasetsGrowByRows) {
  test::TempDir tmp;
  const std::string path = tmp.file("s.h5");
  {
    Hdf5File f(path, Hdf5File::Mode::Write);
    f.create_appendable("/frames/p", {4, 3}, true);
    f.create_appendable("/frames/t", {});
    for (int i = 0; i < 5; ++i) {
      MatXr p = MatXr::Constant(4, 3, double(i));
      f.append("/frames/p", p.data());
      const double t = 0.5 * i;
      f.append("/frames/t", &t);
    }
    f.commit();
  }
  Hdf5File f(path, Hdf5File::Mode::Read);
  std::vector<std::int64_t> shape;
  auto v = f.read_nd("/frames/p", {5, 4, 3}, &shape);
  EXPECT_EQ(v[3 * 12 + 7], 3.0);
  EXPECT_EQ(f.read_matrix("/frames/t", 5, 1)(4, 0), 2.0);
}
