#pragma once
namespace sflsh {
/// Peak resident set size of this process so far (MiB), from /proc/self/status
/// (VmHWM); 0 where unavailable.
double peak_rss_mib();
}  // namespace sflsh
