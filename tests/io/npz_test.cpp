// .npy/.npz reader and writer: round trips, numpy's own files (compressed,
// Fortran order, unicode and object entries), hand-made headers for every
// dtype, and broken or hostile files that must fail with sflsh::Error.
#include "sflsh/io/npz.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include "sflsh/core/error.hpp"
#include "test_support.hpp"

namespace sflsh::io {
namespace {

using test::TempDir;

using test::generated_fixture;

std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
}

// A version-1.0 .npy file with the given header dict text and raw data bytes.
std::string npy(const std::string& dict, const std::string& data) {
  std::string header = dict;
  header += std::string((64 - (10 + header.size() + 1) % 64) % 64, ' ') + "\n";
  std::string out = "\x93NUMPY";
  out += char(1);
  out += char(0);
  out += char(header.size() & 0xff);
  out += char(header.size() >> 8);
  return out + header + data;
}

template <class T>
std::string raw(std::initializer_list<T> values, bool big_endian = false) {
  std::string out;
  for (T v : values) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    if (big_endian) std::reverse(b, b + sizeof(T));
    out.append(b, sizeof(T));
  }
  return out;
}

using test::expect_error;

TEST(Npz, RoundTripStoredAndDeflated) {
  TempDir dir;
  std::map<std::string, NpyArray> arrays;
  arrays["a"] = {{2, 3}, "<f8", {0.1, -2.5, 3e10, 1e-300, 0.0, 7.0}};
  arrays["b"] = {{4}, "<f4", {0.1, 1.0 / 3.0, -5.0, 1e-3}};
  arrays["c"] = {{2, 2}, "<i4", {1, -2, 2147483647, 0}};
  arrays["d"] = {{3}, "<i8", {4294967295.0, -1, 5}};
  arrays["e"] = {{0, 3}, "<f8", {}};
  for (bool compressed : {false, true}) {
    const std::string path = dir.file(compressed ? "z.npz" : "s.npz");
    write_npz(path, arrays, compressed);
    EXPECT_FALSE(std::filesystem::exists(path + ".partial"));
    const auto back = read_npz(path);
    ASSERT_EQ(back.size(), arrays.size());
    for (const auto& [k, a] : arrays) {
      const NpyArray& b = back.at(k);
      EXPECT_EQ(b.shape, a.shape) << k;
      EXPECT_EQ(b.dtype, a.dtype) << k;
      ASSERT_EQ(b.data.size(), a.data.size()) << k;
      for (size_t i = 0; i < a.data.size(); ++i) {
        const double want = a.dtype == "<f4" ? double(float(a.data[i])) : a.data[i];
        EXPECT_EQ(b.data[i], want) << k << "[" << i << "]";
      }
    }
  }
  // Deflate actually compressed something: a long constant array shrinks.
  std::map<std::string, NpyArray> big;
  big["zeros"] = {{10000}, "<f8", std::vector<double>(10000, 0.0)};
  write_npz(dir.file("big_s.npz"), big, false);
  write_npz(dir.file("big_z.npz"), big, true);
  EXPECT_GT(std::filesystem::file_size(dir.file("big_s.npz")), 80000u);
  EXPECT_LT(std::filesystem::file_size(dir.file("big_z.npz")), 2000u);
}

TEST(Npz, WriteRejectsInconsistentArrays) {
  TempDir dir;
  std::map<std::string, NpyArray> arrays;
  arrays["bad"] = {{2, 2}, "<f8", {1, 2, 3}};
  expect_error([&] { write_npz(dir.file("x.npz"), arrays); }, {"x.npz", "'bad'", "(2, 2)"});
  EXPECT_FALSE(std::filesystem::exists(dir.file("x.npz")));
  EXPECT_FALSE(std::filesystem::exists(dir.file("x.npz.partial")));
  arrays["bad"] = {{1}, "<i4", {0.5}};
  expect_error([&] { write_npz(dir.file("x.npz"), arrays); }, {"'bad'", "<i4"});
}

// The committed fixture was written by numpy's savez_compressed (see
// data_tools/smpl_reference.py): deflated, shapedirs in Fortran order, a 0-d
// '<U' array and an object array.
TEST(Npz, ReadsNumpyFilesWithStringsAndObjects) {
  std::map<std::string, std::vector<std::string>> strings;
  const auto arrays = read_npz(generated_fixture("tiny_smpl.npz"), &strings);
  EXPECT_EQ(arrays.count("bs_style"), 0u);  // object array skipped
  EXPECT_EQ(arrays.count("gender"), 0u);    // strings go to `strings`
  ASSERT_EQ(strings.count("gender"), 1u);
  EXPECT_EQ(strings["gender"], std::vector<std::string>{"neutral"});
  ASSERT_EQ(arrays.count("shapedirs"), 1u);
  EXPECT_EQ(arrays.at("shapedirs").shape, (std::vector<std::int64_t>{20, 3, 4}));
  EXPECT_EQ(arrays.at("shapedirs").dtype, "<f4");
  const NpyArray& kt = arrays.at("kintree_table");
  EXPECT_EQ(kt.dtype, "<i8");
  EXPECT_EQ(kt.data[0], 4294967295.0);
  EXPECT_EQ(kt.data[24 + 23], 23.0);

  const auto info = list_npz(generated_fixture("tiny_smpl.npz"));
  bool saw_object = false;
  for (const auto& e : info) saw_object = saw_object || (e.key == "bs_style" && e.dtype == "|O");
  EXPECT_TRUE(saw_object);
}

TEST(Npy, FortranOrderIsTransposedToCOrder) {
  TempDir dir;
  // numpy.asfortranarray([[0, 1, 2], [3, 4, 5]]) stores 0 3 1 4 2 5.
  write_bytes(dir.file("f.npy"),
              npy("{'descr': '<f8', 'fortran_order': True, 'shape': (2, 3), }", raw<double>({0, 3, 1, 4, 2, 5})));
  const NpyArray a = read_npy(dir.file("f.npy"));
  EXPECT_EQ(a.shape, (std::vector<std::int64_t>{2, 3}));
  EXPECT_EQ(a.data, (std::vector<double>{0, 1, 2, 3, 4, 5}));
  // 3-D: element [i, j, k] of shape (2, 2, 2) sits at i + 2 j + 4 k in Fortran order.
  std::vector<double> f(8);
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j)
      for (int k = 0; k < 2; ++k) f[i + 2 * j + 4 * k] = 100 * i + 10 * j + k;
  std::string data;
  for (double v : f) data += raw<double>({v});
  write_bytes(dir.file("f3.npy"), npy("{'descr': '<f8', 'fortran_order': True, 'shape': (2, 2, 2), }", data));
  EXPECT_EQ(read_npy(dir.file("f3.npy")).data, (std::vector<double>{0, 1, 10, 11, 100, 101, 110, 111}));
}

TEST(Npy, EveryDtype) {
  TempDir dir;
  struct Case {
    std::string descr, data;
    std::vector<double> want;
  };
  const std::vector<Case> cases = {
      {"<f2", raw<std::uint16_t>({0x3C00, 0xC000, 0x3555, 0x0001}), {1.0, -2.0, 0.333251953125, std::ldexp(1.0, -24)}},
      {"<f4", raw<float>({1.5f, -0.25f}), {1.5, -0.25}},
      {">f8", raw<double>({1.5, -1e100}, true), {1.5, -1e100}},
      {">i4", raw<std::int32_t>({-7, 65536}, true), {-7, 65536}},
      {"|i1", raw<std::int8_t>({-128, 127}), {-128, 127}},
      {"<i2", raw<std::int16_t>({-300, 300}), {-300, 300}},
      {"<i8", raw<std::int64_t>({-5, 1LL << 40}), {-5, double(1LL << 40)}},
      {"|u1", raw<std::uint8_t>({255, 0}), {255, 0}},
      {"<u2", raw<std::uint16_t>({65535, 1}), {65535, 1}},
      {"<u4", raw<std::uint32_t>({4294967295u, 2}), {4294967295.0, 2}},
      {"<u8", raw<std::uint64_t>({1ULL << 63, 3}), {std::ldexp(1.0, 63), 3}},
      {"|b1", raw<std::uint8_t>({1, 0}), {1, 0}},
  };
  for (const auto& c : cases) {
    const std::string path = dir.file("t.npy");
    const std::string n = std::to_string(c.want.size());
    write_bytes(path, npy("{'descr': '" + c.descr + "', 'fortran_order': False, 'shape': (" + n + ",), }", c.data));
    const NpyArray a = read_npy(path);
    EXPECT_EQ(a.dtype, c.descr);
    EXPECT_EQ(a.data, c.want) << c.descr;
  }
  // A 0-d array has one element; double quotes and a version-2 header work too.
  std::string v2 = "\x93NUMPY";
  const std::string dict = "{\"descr\": \"<f8\", \"fortran_order\": False, \"shape\": ()}\n";
  v2 += char(2);
  v2 += char(0);
  v2 += raw<std::uint32_t>({std::uint32_t(dict.size())});
  write_bytes(dir.file("v2.npy"), v2 + dict + raw<double>({42.0}));
  const NpyArray s = read_npy(dir.file("v2.npy"));
  EXPECT_TRUE(s.shape.empty());
  EXPECT_EQ(s.data, std::vector<double>{42.0});
}

TEST(Npy, BrokenHeadersAndSizesFailCleanly) {
  TempDir dir;
  const std::string p = dir.file("bad.npy");
  auto check = [&](const std::string& bytes, std::initializer_list<std::string> fragments) {
    write_bytes(p, bytes);
    expect_error([&] { read_npy(p); }, fragments);
  };
  const std::string d8 = raw<double>({1, 2, 3, 4});
  check("garbage", {"bad.npy", "magic"});
  check(npy("{'descr': '<f8', 'fortran_order': False, 'shape': (4,), }", d8).substr(0, 40), {"header length"});
  check(npy("not a dict at all", d8), {"malformed"});
  check(npy("{'descr': '<f8', 'shape': (4,), }", d8), {"fortran_order"});
  check(npy("{'descr': '<f8', 'fortran_order': Maybe, 'shape': (4,), }", d8), {"True or False"});
  check(npy("{'descr': '<f8', 'fortran_order': False, 'shape': (4,-1), }", d8), {"non-negative"});
  check(npy("{'descr': [('a', '<f8')], 'fortran_order': False, 'shape': (4,), }", d8), {"structured"});
  check(npy("{'descr': '<c16', 'fortran_order': False, 'shape': (2,), }", d8), {"unsupported dtype", "<c16"});
  check(npy("{'descr': '<f8', 'fortran_order': False, 'shape': (5,), }", d8), {"shape (5,)", "truncated"});
  // Shapes whose element count overflows 64 bits must not wrap around or allocate.
  check(npy("{'descr': '<f8', 'fortran_order': False, 'shape': (4294967296, 4294967296, 16), }", d8),
        {"needs more data"});
  check(npy("{'descr': '<f8', 'fortran_order': False, 'shape': (99999999999999999999999,), }", d8), {"too large"});
  // Object arrays are not numeric data.
  check(npy("{'descr': '|O', 'fortran_order': False, 'shape': (), }", "\x80\x02N."), {"not numeric"});
}

TEST(Npz, TruncatedAndCorruptArchivesFailCleanly) {
  TempDir dir;
  std::map<std::string, NpyArray> arrays;
  arrays["x"] = {{1000}, "<f8", std::vector<double>(1000)};
  for (int i = 0; i < 1000; ++i) arrays["x"].data[i] = std::sin(i);
  write_npz(dir.file("ok.npz"), arrays, true);
  const std::string bytes = read_bytes(dir.file("ok.npz"));

  write_bytes(dir.file("cut.npz"), bytes.substr(0, bytes.size() / 2));
  expect_error([&] { read_npz(dir.file("cut.npz")); }, {"cut.npz", "truncated"});
  expect_error([&] { read_npz(dir.file("missing.npz")); }, {"missing.npz", "not found"});

  // Flip a byte inside the deflated data: the CRC (or inflate) must catch it.
  std::string flipped = bytes;
  flipped[200] = char(flipped[200] ^ 0x5a);
  write_bytes(dir.file("flip.npz"), flipped);
  expect_error([&] { read_npz(dir.file("flip.npz")); }, {"flip.npz", "'x'"});
}

// Random byte corruption of valid files: every outcome is a clean read or an
// sflsh::Error, never a crash or another exception type.
TEST(Npz, RandomCorruptionNeverCrashes) {
  TempDir dir;
  std::map<std::string, NpyArray> arrays;
  arrays["v"] = {{5, 3}, "<f4", std::vector<double>(15, 0.5)};
  arrays["i"] = {{4}, "<i8", {1, 2, 3, 4}};
  std::mt19937 rng(7);
  int errors = 0, reads = 0;
  for (bool compressed : {false, true}) {
    write_npz(dir.file("base.npz"), arrays, compressed);
    const std::string base = read_bytes(dir.file("base.npz"));
    for (int it = 0; it < 100; ++it) {
      std::string b = base;
      const int flips = 1 + int(rng() % 4);
      for (int k = 0; k < flips; ++k) b[rng() % b.size()] = char(rng() & 0xff);
      if (rng() % 4 == 0) b.resize(rng() % b.size());
      write_bytes(dir.file("fuzz.npz"), b);
      try {
        read_npz(dir.file("fuzz.npz"));
        ++reads;
      } catch (const Error&) {
        ++errors;
      }
    }
  }
  // Also corrupt a lone .npy header region directly.
  const std::string good = npy("{'descr': '<f8', 'fortran_order': False, 'shape': (2, 2), }", raw<double>({1, 2, 3, 4}));
  for (int it = 0; it < 200; ++it) {
    std::string b = good;
    b[rng() % 80] = char(rng() & 0xff);
    write_bytes(dir.file("fuzz.npy"), b);
    try {
      read_npy(dir.file("fuzz.npy"));
      ++reads;
    } catch (const Error&) {
      ++errors;
    }
  }
  EXPECT_GT(errors, 100);
  EXPECT_EQ(errors + reads, 400);
}

TEST(NpyArray, ShapeAndFiniteChecksNameKeyAndExpectation) {
  NpyArray a{{2, 3}, "<f8", {1, 2, 3, 4, std::nan(""), 6}};
  EXPECT_EQ(a.size(), 6);
  EXPECT_NO_THROW(a.require_shape({2, -1}, "m.npz", "w"));
  expect_error([&] { a.require_shape({2, 4}, "m.npz", "w"); }, {"m.npz", "'w'", "(2, 3)", "expected (2, 4)"});
  expect_error([&] { a.require_shape({6}, "m.npz", "w"); }, {"expected (6,)"});
  expect_error([&] { a.require_finite("m.npz", "w"); }, {"m.npz", "'w'", "flat index 4"});
}

}  // namespace
}  // namespace sflsh::io
