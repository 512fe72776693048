#pragma once
// Typed errors. The library never prints or exits: it throws, the app reports.
#include <stdexcept>
#include <string>

namespace cisamr {

// Bad input: names the file, the field (a JSON-pointer-like path such as
// "inclusions[3].radius", or "" when the whole file is at fault) and what is wrong.
// The app prints "cisamr: error: FILE: FIELD: what" and exits with code 2.
class InputError : public std::runtime_error {
 public:
  InputError(std::string file, std::string field, std::string problem)
      : std::runtime_error(format(file, field, problem)),
        file_(std::move(file)), field_(std::move(field)), problem_(std::move(problem)) {}
  const std::string& file() const { return file_; }
  const std::string& field() const { return field_; }
  const std::string& problem() const { return problem_; }

 private:
  static std::string format(const std::string& file, const std::string& field,
                            const std::string& problem) {
    std::string s = file.empty() ? std::string("<input>") : printable(file);
    if (!field.empty()) s += ": " + printable(field);
    return s + ": " + printable(problem);
  }
  // One line of valid UTF-8 whatever the input held: control characters and bytes that are
  // not UTF-8 (a file name with a newline, bytes quoted from a binary file) become \n, \xNN.
  static std::string printable(const std::string& text) {
    static constexpr char kHex[] = "0123456789abcdef";
    std::string out;
    for (std::size_t i = 0; i < text.size();) {
      const auto c = static_cast<unsigned char>(text[i]);
      const std::size_t n = c < 0x80 ? 1 : (c >= 0xC2 && c <= 0xDF) ? 2 : (c >> 4) == 0xE ? 3
                                          : (c >= 0xF0 && c <= 0xF4) ? 4 : 0;
      bool valid = n > 0 && i + n <= text.size() && c >= 0x20 && c != 0x7F;
      for (std::size_t k = 1; valid && k < n; ++k)
        valid = (static_cast<unsigned char>(text[i + k]) & 0xC0) == 0x80;
      if (valid) {
        out.append(text, i, n);
        i += n;
        continue;
      }
      if (c == '\n') out += "\\n";
      else if (c == '\t') out += "\\t";
      else if (c == '\r') out += "\\r";
      else out += {'\\', 'x', kHex[c >> 4], kHex[c & 15]};
      ++i;
    }
    return out;
  }
  std::string file_, field_, problem_;
};

// A mesh that cannot be built within the limits (e.g. a gap below the finest level
// that the rules cannot separate). Reported like bad input: the scene asks too much.
class MeshingError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A broken internal invariant: a bug, not bad input. Thrown by the checks of core/check.hpp
// with the file and line; the app reports it as an internal error (exit code 1).
class InternalError : public std::logic_error {
 public:
  using std::logic_error::logic_error;
};

}  // namespace cisamr
