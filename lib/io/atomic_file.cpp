#include "io/atomic_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "core/error.hpp"

namespace cisamr::io {
namespace {

constexpr std::size_t kBufferSize = 1 << 20;  // large writes bypass it

std::atomic<unsigned> temporary_sequence{0};

// ".NAME.tmp.PID.SEQ" in the destination's directory, so that rename() stays on one
// file system (and is therefore atomic). SEQ separates two files of one process.
std::string temporary_name_for(const std::string& path) {
  const std::filesystem::path destination(path);
  std::string name(1, '.');  // appended piece by piece: GCC 12 warns on "." + string
  name += destination.filename().string();
  name += ".tmp.";
  name += std::to_string(::getpid());
  name += '.';
  name += std::to_string(temporary_sequence.fetch_add(1));
  return (destination.parent_path() / name).string();
}

}  // namespace

AtomicFile::AtomicFile(std::string path) : path_(std::move(path)) {
  if (path_.empty() || std::filesystem::path(path_).filename().empty())
    throw InputError(path_, "", "cannot write: not a file name");
  temporary_path_ = temporary_name_for(path_);
  fd_ = ::open(temporary_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd_ < 0) {
    const int error_number = errno;
    throw InputError(path_, "", std::string("cannot write: ") + std::strerror(error_number));
  }
  buffer_.resize(kBufferSize);
}

AtomicFile::~AtomicFile() {
  if (!committed_) discard();
}

void AtomicFile::discard() noexcept {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  if (!temporary_path_.empty()) ::unlink(temporary_path_.c_str());
}

void AtomicFile::fail(int error_number) {
  discard();
  throw InputError(path_, "", std::string("cannot write: ") + std::strerror(error_number));
}

static bool write_all(int fd, const char* data, std::size_t size, int& error_number) {
  while (size > 0) {
    const ssize_t written = ::write(fd, data, size);
    if (written < 0) {
      if (errno == EINTR) continue;
      error_number = errno;
      return false;
    }
    data += written;
    size -= static_cast<std::size_t>(written);
  }
  return true;
}

void AtomicFile::flush_buffer() {
  int error_number = 0;
  if (buffered_ > 0 && !write_all(fd_, buffer_.data(), buffered_, error_number))
    fail(error_number);
  buffered_ = 0;
}

void AtomicFile::write(const void* data, std::size_t size) {
  if (fd_ < 0) fail(EBADF);  // after commit() or a failure
  const char* bytes = static_cast<const char*>(data);
  if (buffered_ + size <= buffer_.size()) {
    std::memcpy(buffer_.data() + buffered_, bytes, size);
    buffered_ += size;
    return;
  }
  flush_buffer();
  if (size >= buffer_.size()) {
    int error_number = 0;
    if (!write_all(fd_, bytes, size, error_number)) fail(error_number);
  } else {
    std::memcpy(buffer_.data(), bytes, size);
    buffered_ = size;
  }
}

void AtomicFile::commit() {
  if (fd_ < 0) fail(EBADF);
  flush_buffer();
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0) fail(errno);
  if (std::rename(temporary_path_.c_str(), path_.c_str()) != 0) fail(errno);
  committed_ = true;
}

}  // namespace cisamr::io
