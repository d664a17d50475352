#pragma once
// The avatar HDF5 file (DESIGN.md §5): one self-describing, versioned file per
// body shape. Dataset names are fixed so other tools can read them (h5py,
// Matlab, ...). All arrays row-major; indices 0-based int32; SI units.
//
//   /meta/format_version   int64 scalar (kAvatarFormatVersion)
//   /meta/units            "metres, kilograms, seconds, pascals"
//   /meta/betas            (B,)      shape parameters the asset was built for
//   /meta/model_hash       string    body_model_hash() of the source body model
//   /meta/model_source     string    "procedural" or the model file path
//   /meta/tool_version     string    "sflsh X.Y.Z"
//   /meta/topology_hash    string    tet_topology_hash(/tet/elements) (mesh/tet_topology_hash.hpp):
//                                    the same for every shape of one template; optional
//                                    (older files have none), checked on reading when present
//   /skeleton/joints_rest  (24,3)    unposed shaped joint positions
//   /skeleton/parents      (24,)     parent index, -1 for the root
//   /skeleton/joint_names  (24,)     strings
//   /skeleton/capsules     (C,8)     bone, p0 xyz, p1 xyz, radius (unposed)
//   /surface/vertices      (V,3)     skin surface, shaped, unposed
//   /surface/faces         (F,3)
//   /surface/weights       (V,24)    LBS weights
//   /surface/posedirs      (V*3,207) optional: pose blend shapes
//   /surface/tet           (V,)      embedding tet of each surface vertex
//   /surface/barycentric   (V,4)     barycentric coordinates in that tet
//   /tet/nodes             (N,3)     shaped, unposed
//   /tet/elements          (T,4)     positively oriented
//   /tet/surface_nodes     (S,)      tet nodes on the outer (skin) surface
//   /tet/node_weights      (N,24)    LBS weights extended into the volume
//   /tet/node_role         (N,)      0 simulated, 1 skinned only, 2 bone (Dirichlet)
//   /tet/region            (T,)      index into /material
//   /tet/frames            (T,9)     local material frame, rows along/through/around
//   /material/names        (R,)      region names
//   /material/parameters   (R,6)     young_along, young_through, young_around (Pa),
//                                    poisson, fung_c (Pa), density (kg/m^3)
//   /basis/handles         (K,3)     control points, unposed
//   /basis/weights         (N,K)     dense W, or
//   /basis/weights_csr/{indptr (N+1,), indices (nnz,), data (nnz,), shape (2,)}
//   /cubature/elastic/{elements (S,), barycentric (S,4), weights (S,)}
//   /cubature/inertia/{elements (S,), barycentric (S,4), weights (S,)}
#include <string>

#include "sflsh/asset/avatar.hpp"

namespace sflsh {

/// Writes `avatar` atomically (temp file + rename). W is stored as CSR when
/// that is smaller than dense.
void write_avatar(const Avatar& avatar, const std::string& path);

/// Reads and validates an avatar file: version, every dataset's shape against
/// the counts it implies, index ranges, finiteness. Throws sflsh::Error naming
/// the file and the dataset.
Avatar read_avatar(const std::string& path);

/// Cross-checks an in-memory avatar (shapes, index ranges, roles, weights);
/// `where` prefixes messages (e.g. the file name).
void validate_avatar(const Avatar& avatar, const std::string& where);

}  // namespace sflsh
