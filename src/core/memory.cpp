#include "sflsh/core/memory.hpp"

#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace sflsh {

double peak_rss_mib() {
  FILE* f = std::fopen("/proc/self/status", "r");
  if (!f) return 0.0;
  char line[256];
  double kib = 0.0;
  while (std::fgets(line, sizeof line, f))
    if (std::strncmp(line, "VmHWM:", 6) == 0) {
      kib = std::atof(line + 6);
      break;
    }
  std::fclose(f);
  return kib / 1024.0;
}

}  // namespace sflsh
