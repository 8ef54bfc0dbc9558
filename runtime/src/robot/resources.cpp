/// @file resources.cpp
/// resident_memory_bytes() (see resources.hpp).
#include <duet/runtime/robot/resources.hpp>

#include <cstdio>
#include <unistd.h>

namespace duet {

std::int64_t resident_memory_bytes() noexcept {
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  if (!f) return -1;
  long long size = 0, resident = 0;
  const int n = std::fscanf(f, "%lld %lld", &size, &resident);
  std::fclose(f);
  const long page = sysconf(_SC_PAGESIZE);
  if (n != 2 || resident < 0 || page <= 0) return -1;
  return static_cast<std::int64_t>(resident) * page;
}

}  // namespace duet
