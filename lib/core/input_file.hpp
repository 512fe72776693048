#pragma once
// Input files read whole (scenes, pack specs, STL surfaces). Only regular files: a FIFO
// would block until a writer comes, a device such as /dev/zero never ends, a directory
// has no bytes. The file is opened without blocking and its size known before reading.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>

#include "core/error.hpp"

namespace cisamr {

// Why `path` cannot be read as an input file, "" when it can.
inline std::string input_file_problem(const std::string& path) {
  struct stat info {};
  if (::stat(path.c_str(), &info) != 0) return std::string("cannot read: ") + std::strerror(errno);
  if (S_ISDIR(info.st_mode)) return "cannot read: is a directory";
  if (!S_ISREG(info.st_mode)) return "cannot read: not a regular file";
  return "";
}

// The bytes of the regular file `path`; InputError(path, "", "cannot read: ...") otherwise.
inline std::string read_input_file(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) throw InputError(path, "", std::string("cannot read: ") + std::strerror(errno));
  struct stat info {};
  if (::fstat(fd, &info) != 0 || !S_ISREG(info.st_mode)) {
    const bool directory = S_ISDIR(info.st_mode);
    ::close(fd);
    throw InputError(path, "", directory ? "cannot read: is a directory" : "cannot read: not a regular file");
  }
  std::string bytes(static_cast<std::size_t>(info.st_size), '\0');
  std::size_t done = 0;
  while (done < bytes.size()) {  // a file that shrinks while read ends early
    const ssize_t n = ::read(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int error_number = errno;
      ::close(fd);
      throw InputError(path, "", std::string("cannot read: ") + std::strerror(error_number));
    }
    if (n == 0) break;
    done += static_cast<std::size_t>(n);
  }
  ::close(fd);
  bytes.resize(done);
  return bytes;
}

}  // namespace cisamr
