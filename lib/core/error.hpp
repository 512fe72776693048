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
    std::string s = file.empty() ? std::string("<input>") : file;
    if (!field.empty()) s += ": " + field;
    return s + ": " + problem;
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
