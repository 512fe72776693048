#include "io/atomic_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "core/error.hpp"

namespace cisamr::io {
namespace {

constexpr std::size_t kBufferSize = 1 << 20;  // large writes bypass it

// ---- Registry of live temporaries, read by the signal handler ----------------------------
// Fixed-size C strings so that the handler touches no allocator and no lock. A slot is
// free (0), being filled (1) or live (2); the handler only reads live slots.
constexpr int kRegistrySlots = 1024;  // a streamed run holds a spool and a piece per partition
constexpr std::size_t kRegistryPathBytes = 4096;
struct RegistrySlot {
  std::atomic<int> state{0};
  char path[kRegistryPathBytes];
};
RegistrySlot registry[kRegistrySlots];
static_assert(std::atomic<int>::is_always_lock_free, "the signal handler needs lock-free atomics");

// The slot now holding `path`, or -1 when the registry is full or the path too long (the
// temporary then works as before, only a signal would leave it behind).
int register_temporary(const std::string& path) {
  if (path.size() >= kRegistryPathBytes) return -1;
  for (int i = 0; i < kRegistrySlots; ++i) {
    int expected = 0;
    if (!registry[i].state.compare_exchange_strong(expected, 1)) continue;
    std::memcpy(registry[i].path, path.c_str(), path.size() + 1);
    registry[i].state.store(2);
    return i;
  }
  return -1;
}

void release_temporary(int slot) noexcept {
  if (slot >= 0) registry[slot].state.store(0);
}

extern "C" void remove_temporaries_and_die(int signal_number) {
  for (RegistrySlot& slot : registry)
    if (slot.state.load() == 2) ::unlink(slot.path);
  std::signal(signal_number, SIG_DFL);
  std::raise(signal_number);  // delivered with the default action once this handler returns
}

// ---- Resolving an output path ------------------------------------------------------------
struct Destination {
  enum class Kind { file, descriptor, device } kind = Kind::file;
  std::string target;       // file, device: where the bytes go after following symlinks
  int descriptor = -1;      // descriptor: the process's own descriptor
  bool exists = false;      // file: there is a regular file to replace
  mode_t mode = 0;          // file: its permissions, kept by the replacement
  int error_number = 0;     // nonzero: cannot write (with `refusal` when errno says too little)
  const char* refusal = nullptr;
};

// N when `path` names this process's descriptor N without opening anything, else -1.
int own_descriptor(const std::string& path) {
  const std::string pid_prefix = "/proc/" + std::to_string(::getpid()) + "/fd/";
  for (const std::string& prefix : {std::string("/dev/fd/"), std::string("/proc/self/fd/"),
                                    std::string("/proc/thread-self/fd/"), pid_prefix}) {
    if (path.size() <= prefix.size() || path.compare(0, prefix.size(), prefix) != 0) continue;
    int n = 0;
    for (std::size_t i = prefix.size(); i < path.size(); ++i) {
      if (path[i] < '0' || path[i] > '9' || n > 1000000) return -1;
      n = n * 10 + (path[i] - '0');
    }
    return n;
  }
  return -1;
}

Destination resolve(const std::string& path) {
  Destination d;
  if (path == "-") {
    d.kind = Destination::Kind::descriptor;
    d.descriptor = STDOUT_FILENO;
    return d;
  }
  // Follow the last component's symlinks ourselves: rename() would replace the link, and
  // /dev/stdout leads to a descriptor rather than to a name that could be reopened.
  std::string current = path;
  struct stat st {};
  for (int hops = 0;; ++hops) {
    if (const int n = own_descriptor(current); n >= 0) {
      d.kind = Destination::Kind::descriptor;
      d.descriptor = n;
      return d;
    }
    if (hops == 40) {
      d.error_number = ELOOP;
      return d;
    }
    if (::lstat(current.c_str(), &st) != 0) {
      d.target = current;  // nothing there yet (or an unreachable folder: open() says why)
      return d;
    }
    if (!S_ISLNK(st.st_mode)) break;
    std::vector<char> link(static_cast<std::size_t>(st.st_size > 0 ? st.st_size : 4095) + 1);
    const ssize_t length = ::readlink(current.c_str(), link.data(), link.size());
    if (length < 0) {
      d.error_number = errno;
      return d;
    }
    const std::filesystem::path next(std::string(link.data(), static_cast<std::size_t>(length)));
    current = next.is_absolute() ? next.string() : (std::filesystem::path(current).parent_path() / next).string();
  }
  d.target = current;
  if (S_ISREG(st.st_mode)) {
    d.exists = true;
    d.mode = st.st_mode & 07777;
  } else if (S_ISCHR(st.st_mode) || S_ISFIFO(st.st_mode)) {
    d.kind = Destination::Kind::device;
  } else if (S_ISDIR(st.st_mode)) {
    d.error_number = EISDIR;
  } else {
    d.error_number = EINVAL;
    d.refusal = S_ISBLK(st.st_mode) ? "is a block device (not overwritten)" : "is a socket";
  }
  return d;
}

std::atomic<unsigned> temporary_sequence{0};

// ".NAME.tmp.PID.SEQ" in the target's directory, so that rename() stays on one file system
// (and is therefore atomic). SEQ separates two files of one process.
std::string temporary_name_for(const std::string& target) {
  const std::filesystem::path destination(target);
  std::string name(1, '.');  // appended piece by piece: GCC 12 warns on "." + string
  name += destination.filename().string();
  name += ".tmp.";
  name += std::to_string(::getpid());
  name += '.';
  name += std::to_string(temporary_sequence.fetch_add(1));
  return (destination.parent_path() / name).string();
}

[[noreturn]] void cannot_write(const std::string& path, int error_number) {
  throw InputError(path, "", std::string("cannot write: ") + std::strerror(error_number));
}

bool write_all(int fd, const char* data, std::size_t size, int& error_number) {
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

thread_local OutputSet* open_set = nullptr;

// resolve(), refusing what no writer can write (InputError(path, "", "cannot write: ...")):
// an empty path, a folder, block device or socket, a symlink loop, a descriptor not open
// for writing, a file path without a file name. AtomicFile and check_writable both start
// here, so they refuse alike.
Destination writable_destination(const std::string& path) {
  if (path.empty()) throw InputError("\"\"", "", "cannot write: the output path is empty");
  const Destination d = resolve(path);
  if (d.refusal) throw InputError(path, "", std::string("cannot write: ") + d.refusal);
  if (d.error_number != 0) cannot_write(path, d.error_number);
  if (d.kind == Destination::Kind::descriptor) {
    const int flags = ::fcntl(d.descriptor, F_GETFL);
    if (flags < 0) cannot_write(path, errno);
    if ((flags & O_ACCMODE) == O_RDONLY) cannot_write(path, EBADF);
  }
  if (d.kind == Destination::Kind::file && std::filesystem::path(d.target).filename().empty())
    throw InputError(path, "", "cannot write: not a file name");
  return d;
}

}  // namespace

void check_writable(const std::string& path) {
  const Destination d = writable_destination(path);
  if (d.kind != Destination::Kind::file) return;
  const std::filesystem::path target(d.target);
  // The temporary is created in the target's folder and renamed there: both need it to be
  // a searchable, writable folder.
  const std::string folder = target.has_parent_path() ? target.parent_path().string() : std::string(".");
  struct stat st {};
  if (::stat(folder.c_str(), &st) != 0) cannot_write(path, errno);
  if (!S_ISDIR(st.st_mode)) cannot_write(path, ENOTDIR);
  if (::access(folder.c_str(), W_OK | X_OK) != 0) cannot_write(path, errno);
}

AtomicFile::AtomicFile(std::string path) : path_(std::move(path)) {
  const Destination d = writable_destination(path_);
  target_ = d.target;
  if (d.kind == Destination::Kind::descriptor) {
    fd_ = d.descriptor;
    owns_fd_ = false;
  } else if (d.kind == Destination::Kind::device) {
    // No O_TRUNC and no O_CREAT: a device or FIFO is written, never replaced.
    fd_ = ::open(target_.c_str(), O_WRONLY | O_CLOEXEC);
    if (fd_ < 0) cannot_write(path_, errno);
  } else {
    temporary_path_ = temporary_name_for(target_);
    // Registered before it exists, so that no signal can find it unrecorded.
    registry_slot_ = register_temporary(temporary_path_);
    fd_ = ::open(temporary_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    if (fd_ < 0) {
      const int error_number = errno;
      release_temporary(registry_slot_);
      registry_slot_ = -1;
      cannot_write(path_, error_number);
    }
    if (d.exists) (void)::fchmod(fd_, d.mode);  // the replacement keeps the old permissions
  }
  buffer_.resize(kBufferSize);
}

AtomicFile::~AtomicFile() {
  if (!committed_) discard();
}

void AtomicFile::discard() noexcept {
  if (fd_ >= 0 && owns_fd_) ::close(fd_);
  fd_ = -1;
  if (!temporary_path_.empty()) ::unlink(temporary_path_.c_str());
  release_temporary(registry_slot_);
  registry_slot_ = -1;
}

void AtomicFile::fail(int error_number) {
  discard();
  cannot_write(path_, error_number);
}

void AtomicFile::flush_buffer() {
  if (buffered_ == 0) return;
  // What the program printed through stdio before must come first.
  if (!owns_fd_) std::fflush(fd_ == STDERR_FILENO ? stderr : stdout);
  int error_number = 0;
  if (!write_all(fd_, buffer_.data(), buffered_, error_number)) fail(error_number);
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

void AtomicFile::flush() {
  if (fd_ < 0) fail(EBADF);
  flush_buffer();
}

void AtomicFile::commit() {
  if (fd_ < 0) fail(EBADF);
  flush_buffer();
  const int fd = fd_;
  fd_ = -1;
  if (!owns_fd_) {
    committed_ = true;
    return;
  }
  if (::close(fd) != 0) fail(errno);
  if (temporary_path_.empty()) {  // a device or FIFO: nothing to rename
    committed_ = true;
    return;
  }
  if (open_set) {
    open_set->held_.push_back({path_, target_, temporary_path_, registry_slot_});
    registry_slot_ = -1;  // the set owns the temporary now
    committed_ = true;
    return;
  }
  if (std::rename(temporary_path_.c_str(), target_.c_str()) != 0) fail(errno);
  release_temporary(registry_slot_);
  registry_slot_ = -1;
  committed_ = true;
}

OutputSet::OutputSet() {
  if (open_set)
    outermost_ = false;
  else
    open_set = this;
}

OutputSet::~OutputSet() {
  if (!outermost_) return;
  open_set = nullptr;
  if (!committed_) discard();
}

void OutputSet::discard() noexcept {
  for (const Held& h : held_) {
    ::unlink(h.temporary.c_str());
    release_temporary(h.registry_slot);
  }
  held_.clear();
}

void OutputSet::commit() {
  if (!outermost_ || committed_) return;
  open_set = nullptr;  // from here on, AtomicFile::commit() renames at once
  committed_ = true;
  for (std::size_t i = 0; i < held_.size(); ++i) {
    if (std::rename(held_[i].temporary.c_str(), held_[i].target.c_str()) != 0) {
      const int error_number = errno;
      const std::string path = held_[i].path;
      held_.erase(held_.begin(), held_.begin() + static_cast<std::ptrdiff_t>(i));
      discard();
      cannot_write(path, error_number);
    }
    release_temporary(held_[i].registry_slot);
  }
  held_.clear();
}

bool is_standard_output(const std::string& path) {
  try {
    const Destination d = resolve(path);
    return d.kind == Destination::Kind::descriptor && d.descriptor == STDOUT_FILENO;
  } catch (const std::exception&) {
    return false;
  }
}

void install_signal_cleanup() {
  for (const int signal_number : {SIGINT, SIGTERM, SIGHUP, SIGPIPE}) {
    struct sigaction current {};
    if (::sigaction(signal_number, nullptr, &current) != 0 || current.sa_handler != SIG_DFL) continue;
    struct sigaction action {};
    action.sa_handler = remove_temporaries_and_die;
    sigemptyset(&action.sa_mask);
    ::sigaction(signal_number, &action, nullptr);
  }
}

std::vector<std::string> live_temporaries() {
  std::vector<std::string> paths;
  for (const RegistrySlot& slot : registry)
    if (slot.state.load() == 2) paths.emplace_back(slot.path);
  return paths;
}

}  // namespace cisamr::io
