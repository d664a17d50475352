#pragma once
// 64-bit FNV-1a over bytes: a stable content key for cache file names (not
// cryptographic). (body_model_hash feeds whole 64-bit words instead, for speed
// on megabytes of blend shapes; its keys are a different function.)
#include <cstddef>
#include <cstdint>
#include <string>

namespace sflsh {

class Fnv1a64 {
 public:
  void add(const void* data, std::size_t bytes);
  void add(const std::string& text) { add(text.data(), text.size()); }
  std::uint64_t value() const { return h_; }
  /// 16 lower-case hex digits.
  std::string hex() const;

 private:
  std::uint64_t h_ = 1469598103934665603ull;
};

}  // namespace sflsh
