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
#include <string_view>
#include <system_error>
#include <vector>

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

// Readers that read several files (a .pvtu and its pieces, TetGen's .node and .ele): one
// input holds them all, separated by kFileSeparator lines, written under the given names to
// one folder per process (removed at exit). Parts beyond the names are dropped, missing
// ones are not written (a missing piece is input too).
inline constexpr std::string_view kFileSeparator = "\n@@next-file@@\n";

class ScratchFolder {
 public:
  explicit ScratchFolder(std::vector<std::string> names) : names_(std::move(names)) {
    const std::filesystem::path dir =
        std::filesystem::is_directory("/dev/shm") ? "/dev/shm" : std::filesystem::temp_directory_path();
    folder_ = dir / ("cisamr_fuzz_" + std::to_string(::getpid()));
    std::filesystem::create_directories(folder_);
  }
  ~ScratchFolder() {
    std::error_code ignored;
    std::filesystem::remove_all(folder_, ignored);
  }
  ScratchFolder(const ScratchFolder&) = delete;
  ScratchFolder& operator=(const ScratchFolder&) = delete;

  // Writes the parts of the input; returns the path of the first name (the one to read).
  std::string write(const std::uint8_t* data, std::size_t size) const {
    const std::string_view input(reinterpret_cast<const char*>(data), size);
    std::size_t start = 0;
    for (std::size_t k = 0; k < names_.size(); ++k) {
      const std::string path = (folder_ / names_[k]).string();
      std::remove(path.c_str());
      if (start > input.size()) continue;
      const std::size_t end = std::min(input.find(kFileSeparator, start), input.size());
      const std::string_view part = input.substr(start, end - start);
      std::FILE* f = std::fopen(path.c_str(), "wb");
      if (f == nullptr || (!part.empty() && std::fwrite(part.data(), 1, part.size(), f) != part.size()) ||
          std::fclose(f) != 0) {
        std::perror(path.c_str());
        std::abort();  // the harness, not the reader, failed
      }
      start = end + kFileSeparator.size();
    }
    return (folder_ / names_.front()).string();
  }

 private:
  std::vector<std::string> names_;
  std::filesystem::path folder_;
};

}  // namespace cisamr::fuzz
