#include <gtest/gtest.h>
#include <hdf5.h>

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

TEST(Hdf5File, AFileOfAnotherTypeIsNamedAsNotHdf5) {
  // A PNG signature and some bytes: refused up front, before libhdf5 tries to
  // open it (mutation check M53, scripts/results/mutation.md).
  test::TempDir tmp;
  const std::string path = tmp.file("picture.h5");
  {
    std::ofstream f(path, std::ios::binary);
    f << "\x89PNG\r\n\x1a\n" << std::string(600, 'x');
  }
  test::expect_error([&] { Hdf5File f(path, Hdf5File::Mode::Read); }, {"picture.h5", "not an HDF5 file"});
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

TEST(Hdf5File, StringsAreStoredFixedLengthAndRoundTrip) {
  test::TempDir tmp;
  const std::string path = tmp.file("s.h5");
  const std::vector<std::string> names = {"", "pelvis", "a longer name with spaces  ", "h\xc3\xa4nde", std::string(300, 'x')};
  {
    Hdf5File f(path, Hdf5File::Mode::Write);
    f.write_strings("/names", names);
    f.write_strings("/none", {});
    f.write_string("/one", "metres");
    test::expect_error([&] { f.write_strings("/nul", {std::string("a\0b", 3)}); }, {"/nul", "NUL"});
    f.commit();
  }
  // Read back through the raw API: fixed-length, as wide as the longest value.
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  const hid_t ds = H5Dopen2(file, "/names", H5P_DEFAULT);
  const hid_t type = H5Dget_type(ds);
  EXPECT_EQ(H5Tis_variable_str(type), 0);
  EXPECT_EQ(H5Tget_size(type), 300u);
  H5Tclose(type);
  H5Dclose(ds);
  H5Fclose(file);
  const Hdf5File f(path, Hdf5File::Mode::Read);
  EXPECT_EQ(f.read_strings("/names"), names);
  EXPECT_TRUE(f.read_strings("/none").empty());
  EXPECT_EQ(f.read_string("/one"), "metres");
}

namespace {
// Writes one dataset of `n` values of the HDF5 type `type` (data: `mem` bytes in `mem_type`).
void write_raw_dataset(const std::string& path, const char* name, hid_t type, hid_t mem_type, const void* mem, hsize_t n) {
  const hid_t file = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  const hid_t space = H5Screate_simple(1, &n, nullptr);
  const hid_t ds = H5Dcreate2(file, name, type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  ASSERT_GE(ds, 0);
  ASSERT_GE(H5Dwrite(ds, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, mem), 0);
  H5Dclose(ds);
  H5Sclose(space);
  H5Fclose(file);
}
}  // namespace

TEST(Hdf5File, VariableLengthStringsAreRefusedWithoutReadingTheHeap) {
  // What sflsh wrote before, and h5py writes for `str`: variable-length strings.
  test::TempDir tmp;
  const std::string path = tmp.file("vlen.h5");
  const hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, H5T_VARIABLE);
  const char* values[2] = {"pelvis", "left_hip"};
  write_raw_dataset(path, "/joint_names", type, type, values, 2);
  H5Tclose(type);
  const Hdf5File f(path, Hdf5File::Mode::Read);
  test::expect_error([&] { f.read_strings("/joint_names"); },
                     {"vlen.h5", "/joint_names", "variable-length strings", "sflsh precompute"});
}

TEST(Hdf5File, UnusualNumberTypesAreRefused) {
  // A 16-byte float (x86 long double) and a 12-bit integer in a 16-bit slot:
  // libhdf5 1.10 converts such types past its buffers on damaged files
  // (tests/fuzz_regressions/body_model_h5/), so only IEEE float32/64 and plain integers are read.
  test::TempDir tmp;
  const long double ld[3] = {1, 2, 3};
  write_raw_dataset(tmp.file("ld.h5"), "/x", H5T_NATIVE_LDOUBLE, H5T_NATIVE_LDOUBLE, ld, 3);
  test::expect_error([&] { Hdf5File(tmp.file("ld.h5"), Hdf5File::Mode::Read).read_matrix("/x"); },
                     {"ld.h5", "/x", "unsupported number type (16 bytes)"});
  const hid_t i12 = H5Tcopy(H5T_STD_I16LE);
  H5Tset_precision(i12, 12);
  const short s[2] = {5, -7};
  write_raw_dataset(tmp.file("i12.h5"), "/y", i12, H5T_NATIVE_SHORT, s, 2);
  H5Tclose(i12);
  test::expect_error([&] { Hdf5File(tmp.file("i12.h5"), Hdf5File::Mode::Read).read_scalar("/y"); },
                     {"i12.h5", "/y", "unsupported number type"});
  // The usual types still read: big-endian float32 and uint8.
  const float fl[2] = {1.5f, -2.25f};
  write_raw_dataset(tmp.file("f.h5"), "/f", H5T_IEEE_F32BE, H5T_NATIVE_FLOAT, fl, 2);
  EXPECT_EQ(Hdf5File(tmp.file("f.h5"), Hdf5File::Mode::Read).read_matrix("/f", 2, 1)(1, 0), -2.25);
  const unsigned char u[2] = {200, 3};
  write_raw_dataset(tmp.file("u.h5"), "/u", H5T_STD_U8LE, H5T_NATIVE_UCHAR, u, 2);
  EXPECT_EQ(Hdf5File(tmp.file("u.h5"), Hdf5File::Mode::Read).read_matrix("/u", 2, 1)(0, 0), 200.0);
}

// A count stored as a double (result files' /meta/newton_iters) is read as an int only when it is
// a whole number in range: a fuzzed 4.2e9 used to be converted to int (undefined behaviour).
TEST(Hdf5File, IntScalarIsAWholeNumberInRange) {
  test::TempDir tmp;
  const std::string path = tmp.file("c.h5");
  {
    Hdf5File f(path, Hdf5File::Mode::Write);
    f.write_scalar("/ok", 7.0);
    f.write_scalar("/big", 4.2e9);
    f.write_scalar("/half", 2.5);
    f.write_scalar("/nan", std::numeric_limits<double>::quiet_NaN());
    f.write_scalar("/negative", -1.0);
    f.commit();
  }
  Hdf5File f(path, Hdf5File::Mode::Read);
  EXPECT_EQ(f.read_int_scalar("/ok", 0, 100), 7);
  EXPECT_EQ(f.read_int_scalar("/ok", 7, 7), 7);
  for (const char* name : {"/big", "/half", "/nan", "/negative"}) {
    try {
      f.read_int_scalar(name, 0, 1000000);
      ADD_FAILURE() << name << " accepted";
    } catch (const Error& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("c.h5: dataset " + std::string(name)), std::string::npos) << what;
      // NaN is refused by every reader already (read_nd), the others by the range check.
      EXPECT_NE(what.find(std::string(name) == "/nan" ? "non-finite" : "whole number in [0, 1000000]"),
                std::string::npos)
          << what;
    }
  }
}
