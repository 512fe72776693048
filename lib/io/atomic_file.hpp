#pragma once
// Output that appears all at once or not at all (DESIGN.md §6): bytes go to a temporary
// file next to the destination (".NAME.tmp.PID.SEQ"), commit() renames it over the
// destination, and a destructor that runs before commit() (error, exception, early return)
// deletes the temporary. A reader therefore never sees a half-written file under the
// final name. No fsync: this protects against a failed or killed run, not a power cut.
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace cisamr::io {

class AtomicFile {
 public:
  // Creates the temporary. Throws InputError(path, "", "cannot write: <strerror>").
  explicit AtomicFile(std::string path);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  // Appends bytes (buffered). Throws InputError on a failed write.
  void write(const void* data, std::size_t size);
  void write(std::string_view text) { write(text.data(), text.size()); }

  // Flushes, closes and renames the temporary over the destination. Throws InputError
  // (and removes the temporary) when any of that fails. Further writes are an error.
  void commit();

  const std::string& path() const { return path_; }
  const std::string& temporary_path() const { return temporary_path_; }
  bool committed() const { return committed_; }

 private:
  void flush_buffer();
  [[noreturn]] void fail(int error_number);
  void discard() noexcept;

  std::string path_, temporary_path_;
  int fd_ = -1;
  bool committed_ = false;
  std::vector<char> buffer_;
  std::size_t buffered_ = 0;
};

}  // namespace cisamr::io
