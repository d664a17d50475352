#include <gtest/gtest.h>

#include <filesystem>

#include "sflsh/asset/avatar_file.hpp"
#include "sflsh/body/smpl_skeleton.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/io/hdf5_file.hpp"
#include "sflsh/mesh/tet_topology_hash.hpp"
#include "test_support.hpp"

using namespace sflsh;

namespace {

// Two tets sharing a face, 24 joints in a line, one handle.
Avatar tiny_avatar() {
  Avatar a;
  a.betas = VecX::Constant(3, 0.5);
  a.model_hash = "abc123";
  a.model_source = "procedural";
  a.joints_rest = Points::Zero(24, 3);
  for (int j = 0; j < 24; ++j) a.joints_rest(j, 1) = 0.05 * j;
  a.parents.assign(kSmplParents.begin(), kSmplParents.end());
  for (auto n : kSmplJointNames) a.joint_names.emplace_back(n);
  a.capsules.push_back({3, Vec3(0, 0, 0), Vec3(0, 0.2, 0), 0.1});
  a.tet.nodes.resize(5, 3);
  a.tet.nodes << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1;
  a.tet.elements.resize(2, 4);
  a.tet.elements << 0, 1, 2, 3, 1, 2, 3, 4;
  a.surface_rest = a.tet.nodes;
  a.surface_faces.resize(2, 3);
  a.surface_faces << 0, 1, 2, 1, 2, 4;
  a.surface_weights = MatXr::Zero(5, 24);
  a.surface_weights.col(0).setOnes();
  a.surface_tet = VecXi::Zero(5);
  a.surface_bary = MatXr::Constant(5, 4, 0.25);
  a.node_weights = a.surface_weights;
  a.node_role = VecXi::Zero(5);
  a.node_role[0] = int(NodeRole::Bone);
  a.surface_nodes = VecXi::LinSpaced(5, 0, 4);
  a.tet_region = VecXi::Zero(2);
  a.tet_frames = MatXr::Zero(2, 9);
  a.tet_frames.row(0) << 1, 0, 0, 0, 1, 0, 0, 0, 1;
  a.tet_frames.row(1) = a.tet_frames.row(0);
  a.materials.push_back(RegionMaterial{"torso"});
  a.handles.resize(1, 3);
  a.handles << 1, 1, 1;
  MatXr W = MatXr::Zero(5, 1);
  W(4, 0) = 1.0;
  W(1, 0) = 0.25;
  a.W = W.sparseView();
  a.elastic.elements = VecXi::Zero(1);
  a.elastic.barycentric = MatXr::Constant(1, 4, 0.25);
  a.elastic.weights = VecX::Constant(1, 0.3);
  a.inertia = a.elastic;
  return a;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(AvatarFile, RoundTripKeepsEveryArray) {
  test::TempDir tmp;
  Avatar a = tiny_avatar();
  write_avatar(a, tmp.file("a.h5"));
  Avatar b = read_avatar(tmp.file("a.h5"));
  EXPECT_EQ(b.betas, a.betas);
  EXPECT_EQ(b.model_hash, a.model_hash);
  EXPECT_EQ(b.joints_rest, a.joints_rest);
  EXPECT_EQ(b.parents, a.parents);
  EXPECT_EQ(b.joint_names, a.joint_names);
  ASSERT_EQ(b.capsules.size(), 1u);
  EXPECT_EQ(b.capsules[0].p1, a.capsules[0].p1);
  EXPECT_EQ(b.tet.nodes, a.tet.nodes);
  EXPECT_EQ(b.tet.elements, a.tet.elements);
  EXPECT_EQ(b.node_role, a.node_role);
  EXPECT_EQ(b.materials[0].young_along, a.materials[0].young_along);
  EXPECT_EQ(MatXr(b.W), MatXr(a.W));
  EXPECT_EQ(b.elastic.weights, a.elastic.weights);
  EXPECT_EQ(b.inertia.barycentric, a.inertia.barycentric);
}

TEST(AvatarFile, SparseWeightsAreStoredAsCsr) {
  test::TempDir tmp;
  Avatar a = tiny_avatar();
  // 200 nodes, 10 handles, one non-zero per row: CSR pays.
  a.tet.nodes = Points::Random(200, 3);
  a.node_weights = MatXr::Zero(200, 24);
  a.node_weights.col(0).setOnes();
  a.node_role = VecXi::Zero(200);
  a.handles = Points::Random(10, 3);
  std::vector<Eigen::Triplet<double>> t;
  for (int i = 0; i < 200; ++i) t.emplace_back(i, i % 10, 0.5);
  a.W.resize(200, 10);
  a.W.setFromTriplets(t.begin(), t.end());
  write_avatar(a, tmp.file("s.h5"));
  io::Hdf5File f(tmp.file("s.h5"), io::Hdf5File::Mode::Read);
  EXPECT_TRUE(f.has("/basis/weights_csr/indptr"));
  EXPECT_FALSE(f.has("/basis/weights"));
  EXPECT_EQ(MatXr(read_avatar(tmp.file("s.h5")).W), MatXr(a.W));
}

TEST(AvatarFile, RejectsBadContentNamingTheDataset) {
  test::TempDir tmp;
  Avatar a = tiny_avatar();
  a.tet.elements(1, 3) = 7;  // out of range
  EXPECT_NE(error_of([&] { write_avatar(a, tmp.file("x.h5")); }).find("/tet/elements"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(tmp.file("x.h5")));

  // A file with a wrong version and one with a mismatched array.
  a = tiny_avatar();
  write_avatar(a, tmp.file("ok.h5"));
  {
    io::Hdf5File f(tmp.file("v.h5"), io::Hdf5File::Mode::Write);
    f.write_scalar("/meta/format_version", std::int64_t(99));
    f.commit();
  }
  EXPECT_NE(error_of([&] { read_avatar(tmp.file("v.h5")); }).find("/meta/format_version"), std::string::npos);
  EXPECT_NE(error_of([&] { read_avatar(tmp.file("missing.h5")); }).find("not found"), std::string::npos);

  // Truncated file.
  std::filesystem::copy_file(tmp.file("ok.h5"), tmp.file("t.h5"));
  std::filesystem::resize_file(tmp.file("t.h5"), std::filesystem::file_size(tmp.file("t.h5")) / 3);
  EXPECT_FALSE(error_of([&] { read_avatar(tmp.file("t.h5")); }).empty());
}

TEST(AvatarFile, RejectsNonFiniteNodes) {
  test::TempDir tmp;
  Avatar a = tiny_avatar();
  write_avatar(a, tmp.file("ok.h5"));
  // Rewrite the file with a NaN in /tet/nodes by copying datasets through a new writer.
  Avatar bad = a;
  bad.tet.nodes(2, 1) = std::nan("");
  // validate_avatar does not look at values; the HDF5 reader does.
  io::Hdf5File f(tmp.file("n.h5"), io::Hdf5File::Mode::Write);
  f.write_scalar("/meta/format_version", std::int64_t(kAvatarFormatVersion));
  f.write_nd("/meta/betas", a.betas.data(), {a.betas.size()});
  f.write_string("/meta/model_hash", "x");
  f.write_string("/meta/model_source", "x");
  f.write_matrix("/skeleton/joints_rest", a.joints_rest);
  f.write_nd("/skeleton/parents", a.parents.data(), {24});
  f.write_strings("/skeleton/joint_names", a.joint_names);
  const double no_capsules[1] = {0.0};
  f.write_nd("/skeleton/capsules", no_capsules, {0, 8});
  f.write_matrix("/surface/vertices", bad.tet.nodes);
  f.commit();
  std::string err = error_of([&] { read_avatar(tmp.file("n.h5")); });
  EXPECT_NE(err.find("/surface/vertices"), std::string::npos) << err;
  EXPECT_NE(err.find("non-finite"), std::string::npos) << err;
}

// /meta/topology_hash: the element array's hash (FNV-1a 64 over the int32 indices, by hand
// below), checked on reading; a file without it (written before it existed) still reads.
TEST(AvatarFile, TopologyHashIsStoredCheckedAndOptional) {
  test::TempDir tmp;
  const Avatar a = tiny_avatar();
  write_avatar(a, tmp.file("t.h5"));
  {
    io::Hdf5File f(tmp.file("t.h5"), io::Hdf5File::Mode::Read);
    EXPECT_EQ(f.read_string("/meta/topology_hash"), tet_topology_hash(a.tet.elements));
  }
  std::string out;
  auto python = [&](const std::string& code) {
    return test::run_command("/usr/bin/python3 -c \"import h5py, sys\nwith h5py.File(sys.argv[1], 'r+') as f:\n" +
                                 code + "\" " + tmp.file("t.h5"),
                             &out);
  };
  // Tets in the other order: the stored hash no longer matches.
  ASSERT_EQ(python("    e = f['/tet/elements'][...]\n    e[[0, 1]] = e[[1, 0]]\n    f['/tet/elements'][...] = e"), 0)
      << out;
  EXPECT_NE(error_of([&] { read_avatar(tmp.file("t.h5")); }).find("dataset /meta/topology_hash is "),
            std::string::npos);
  ASSERT_EQ(python("    del f['/meta/topology_hash']"), 0) << out;
  EXPECT_EQ(read_avatar(tmp.file("t.h5")).tet.elements.row(0), a.tet.elements.row(1));
}
