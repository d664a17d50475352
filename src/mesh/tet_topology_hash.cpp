#include "sflsh/mesh/tet_topology_hash.hpp"

#include <cstdint>

#include "sflsh/core/fnv_hash.hpp"

namespace sflsh {

std::string tet_topology_hash(const Tets& elements) {
  Fnv1a64 h;
  for (Eigen::Index t = 0; t < elements.rows(); ++t)
    for (int c = 0; c < 4; ++c) {
      const auto v = static_cast<std::uint32_t>(elements(t, c));
      const unsigned char bytes[4] = {static_cast<unsigned char>(v), static_cast<unsigned char>(v >> 8),
                                      static_cast<unsigned char>(v >> 16), static_cast<unsigned char>(v >> 24)};
      h.add(bytes, 4);
    }
  return h.hex();
}

}  // namespace sflsh
