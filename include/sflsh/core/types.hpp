#pragma once
// Common Eigen types. Point sets are row-major "#N by 3" so that a row is a
// point and the memory layout matches HDF5/numpy (C order) files one to one.
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace sflsh {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using VecX = Eigen::VectorXd;
using MatX = Eigen::MatrixXd;
using VecXi = Eigen::VectorXi;

/// #N by 3 points (metres unless said otherwise), one point per row.
using Points = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
/// #F by 3 triangle vertex indices (0-based, counter-clockwise seen from outside).
using Triangles = Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>;
/// #T by 4 tetrahedron node indices (0-based, positive orientation:
/// (x1-x0)·((x2-x0)×(x3-x0)) > 0).
using Tets = Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor>;
/// Dense row-major matrix (e.g. #N by 24 skinning weights).
using MatXr = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

}  // namespace sflsh
