#pragma once
// The process's memory as the operating system sees it (Linux; elsewhere these do nothing
// and report 0).
#include <cstdint>
#include <fstream>
#include <string>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace cisamr {

// Gives the pages of freed heap memory back to the system. A stage that frees millions of
// small nodes (hash maps) leaves them in the heap, resident, where only small allocations
// can reuse them; the next stage's large arrays would add to them.
inline void release_free_memory() {
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
}

// Peak resident set size of this process so far (VmHWM), bytes; 0 where unknown.
inline std::int64_t peak_resident_bytes() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::stoll(line.substr(6)) * 1024;
  return 0;
}

}  // namespace cisamr
