#include "sflsh/core/fnv_hash.hpp"

#include <iomanip>
#include <sstream>

namespace sflsh {

void Fnv1a64::add(const void* data, std::size_t bytes) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < bytes; ++i) h_ = (h_ ^ p[i]) * 1099511628211ull;
}

std::string Fnv1a64::hex() const {
  std::ostringstream o;
  o << std::hex << std::setw(16) << std::setfill('0') << h_;
  return o.str();
}

}  // namespace sflsh
