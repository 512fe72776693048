#pragma once
// What every fuzz target shares. A target feeds one input to one reader: an InputError is
// the expected answer to bad input; any other exception escapes (libFuzzer reports it as a
// crash, the replay driver as a failure), as do crashes, hangs and sanitizer reports.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>

#include "core/error.hpp"

namespace cisamr::fuzz {

template <class Read>
int expect_input_error_only(Read&& read) {
  try {
    read();
  } catch (const InputError&) {
  }
  return 0;
}

// The readers that take a path get the input through one scratch file per process (in
// /dev/shm when there is one, so that a run does not wear the disk), removed at exit.
class ScratchFile {
 public:
  explicit ScratchFile(const std::string& extension) {
    const std::filesystem::path dir =
        std::filesystem::is_directory("/dev/shm") ? "/dev/shm" : std::filesystem::temp_directory_path();
    path_ = (dir / ("cisamr_fuzz_" + std::to_string(::getpid()) + extension)).string();
  }
  ~ScratchFile() { std::remove(path_.c_str()); }
  ScratchFile(const ScratchFile&) = delete;
  ScratchFile& operator=(const ScratchFile&) = delete;

  const std::string& write(const std::uint8_t* data, std::size_t size) const {
    std::FILE* f = std::fopen(path_.c_str(), "wb");
    if (f == nullptr || (size > 0 && std::fwrite(data, 1, size, f) != size) || std::fclose(f) != 0) {
      std::perror(path_.c_str());
      std::abort();  // the harness, not the reader, failed
    }
    return path_;
  }

 private:
  std::string path_;
};

}  // namespace cisamr::fuzz
