#pragma once
// Output that appears all at once or not at all (DESIGN.md §6). README.md, "Output paths".
//
// A regular file is written to a temporary beside it (".NAME.tmp.PID.SEQ") and commit()
// renames the temporary over it, so a reader never sees a half-written file under the final
// name; a destructor that runs before commit() (error, exception, early return) deletes the
// temporary. No fsync: this protects against a failed or killed run, not a power cut.
//
// What the path names decides how it is written:
//   a symlink          followed to its final target: the temporary goes beside the target
//                      and the rename replaces the target, so the link stays a link;
//   "-"                standard output, written directly;
//   /dev/stdout, /dev/fd/N, /proc/self/fd/N
//                      this process's descriptor N, written directly (never reopened, so a
//                      shell redirection keeps its offset and nothing is renamed over /dev);
//   a character device or a FIFO
//                      opened and written directly (bytes arrive as they are produced);
//   a directory, a block device, a socket
//                      refused: InputError(path, "", "cannot write: ...") at construction.
// Errors always name the path as given, never the temporary.
//
// Temporaries are recorded in a process-wide registry; install_signal_cleanup() makes
// SIGINT, SIGTERM, SIGHUP and SIGPIPE delete them before the process dies of the signal.
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace cisamr::io {

class AtomicFile {
 public:
  // Resolves the path and opens the temporary (or the direct destination). Throws
  // InputError(path, "", "cannot write: <why>").
  explicit AtomicFile(std::string path);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  // Appends bytes (buffered). Throws InputError on a failed write.
  void write(const void* data, std::size_t size);
  void write(std::string_view text) { write(text.data(), text.size()); }
  // Writes out what is buffered, so that the temporary can be read back (a spool that is
  // never committed: its destructor deletes it). Throws InputError on a failed write.
  void flush();

  // Flushes, closes and renames the temporary over the destination; a direct destination
  // is only flushed. Inside an open OutputSet the rename waits for the set's commit().
  // Throws InputError (and removes the temporary) when any of that fails. Further writes
  // are an error.
  void commit();

  const std::string& path() const { return path_; }
  // "" for a direct destination (nothing is renamed).
  const std::string& temporary_path() const { return temporary_path_; }
  bool committed() const { return committed_; }

 private:
  void flush_buffer();
  [[noreturn]] void fail(int error_number);
  void discard() noexcept;

  std::string path_, target_, temporary_path_;
  int fd_ = -1;
  bool owns_fd_ = true;    // false for a descriptor this process already had (stdout)
  int registry_slot_ = -1;  // the temporary's entry in the signal-cleanup registry
  bool committed_ = false;
  std::vector<char> buffer_;
  std::size_t buffered_ = 0;
};

// All-or-nothing for several outputs. While a set is open on a thread, AtomicFile::commit()
// on that thread only completes the temporary and hands it to the set; the set's commit()
// renames them all, in order, at the very end. A set destroyed before commit() (an error in
// any output, or in anything after the first write) deletes every temporary it holds, so
// no output of a failed run appears under its final name. A set opened while another is
// open joins the outer one: its commit() and destructor leave everything to the outer set.
// Direct destinations (stdout, devices, FIFOs) are written as they go and are not held back.
//
// Once every temporary is complete a rename can only fail on an I/O error; outputs renamed
// before such a failure stay (the old contents are gone by then).
class OutputSet {
 public:
  OutputSet();
  ~OutputSet();
  OutputSet(const OutputSet&) = delete;
  OutputSet& operator=(const OutputSet&) = delete;

  // Renames every held temporary onto its destination. Throws InputError naming the
  // output whose rename failed (the temporaries not yet renamed are deleted).
  void commit();

 private:
  friend class AtomicFile;
  struct Held {
    std::string path, target, temporary;
    int registry_slot;
  };
  void discard() noexcept;

  std::vector<Held> held_;
  bool outermost_ = true;
  bool committed_ = false;
};

// Throws what AtomicFile(path) would, without creating anything: for a file, when its
// folder is missing or not writable (or the path names a folder, a block device, a socket, a
// symlink loop); for a descriptor, when it is not open for writing. Devices and FIFOs are
// not opened (a FIFO would wait for its reader). A command checks its outputs with it before
// the work whose results they hold, so that a mistyped folder fails at once, not after an
// hour of meshing.
void check_writable(const std::string& path);

// True when `path` is this process's standard output: "-", /dev/stdout, /dev/fd/1,
// /proc/self/fd/1 (directly or through symlinks). A command whose data goes there prints
// its summary on standard error instead. Never throws.
bool is_standard_output(const std::string& path);

// Installs handlers for SIGINT, SIGTERM, SIGHUP and SIGPIPE (each only where the signal
// still has its default action, so an ignored SIGHUP stays ignored) that delete every live
// temporary and then die of the same signal with the default action. Async-signal-safe:
// the handler only reads fixed-size C strings and calls unlink(), signal() and raise().
// Called once by the application; the library itself never installs handlers.
void install_signal_cleanup();

// The temporaries the registry holds now (for tests and diagnostics).
std::vector<std::string> live_temporaries();

}  // namespace cisamr::io
