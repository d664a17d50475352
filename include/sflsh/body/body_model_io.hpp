#pragma once
// Loading and saving SMPL-format body models.
//  - HDF5 (the project's canonical format; data_tools/smpl_pkl_to_h5.py writes it):
//      /meta/format_version (int), /meta/units ("metres"), /meta/source
//      /v_template (V,3) /f (F,3) /shapedirs (V,3,B) /posedirs (V,3,207)
//      /J_regressor (24,V) dense, or /J_regressor_csr/{indptr,indices,data,shape}
//      /weights (V,24) /kintree_table (2,24) /joint_names (24 strings, optional)
//      /shape_meanings (B strings, optional)
//  - SMPL .npz (numpy zip as distributed): keys v_template f shapedirs posedirs
//    J_regressor weights kintree_table; float32/float64/int, stored or deflated.
#include <string>

#include "sflsh/body/body_model.hpp"

namespace sflsh {

inline constexpr int kBodyModelFormatVersion = 1;

/// "procedural" -> the built-in body; otherwise a path whose extension picks
/// the reader (.h5/.hdf5 or .npz). Throws sflsh::Error naming file and key.
BodyModel load_body_model(const std::string& spec);

BodyModel read_body_model_hdf5(const std::string& path);
BodyModel read_body_model_npz(const std::string& path);
/// Writes atomically (no half-written file on failure).
void write_body_model_hdf5(const BodyModel& model, const std::string& path);

/// Content hash (hex) of all model arrays: keys caches of template-stage work.
std::string body_model_hash(const BodyModel& model);

}  // namespace sflsh
