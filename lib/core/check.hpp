#pragma once
// Internal checks, two kinds (DESIGN.md §10):
//   CISAMR_CHECK(condition, what)        always on: guards against wrong output (a mesh
//                                        that is not conforming, a tet from a broken rule);
//                                        cheap next to the work around it.
//   CISAMR_DEBUG_CHECK(condition, what)  an invariant too costly to test in a hot loop of
//                                        a Release build, or one the tests already prove
//                                        (fixed tables, index bounds): compiled out under
//                                        NDEBUG, where its condition is not evaluated (so it
//                                        must have no side effects).
// A failed check throws InternalError "file:line: what" (a bug, not bad input); `what`
// (a string) is built only when the check fails.
#include <string>

#include "core/error.hpp"

namespace cisamr::detail {

[[noreturn, gnu::cold, gnu::noinline]] inline void check_failed(const char* file, int line, const std::string& what) {
  throw InternalError(std::string(file) + ":" + std::to_string(line) + ": " + what);
}

}  // namespace cisamr::detail

#define CISAMR_CHECK(condition, what)                                                   \
  do {                                                                                  \
    if (!(condition)) [[unlikely]] ::cisamr::detail::check_failed(__FILE__, __LINE__, what); \
  } while (false)

#ifdef NDEBUG
#define CISAMR_DEBUG_CHECK(condition, what) \
  do {                                      \
  } while (false)
#else
#define CISAMR_DEBUG_CHECK(condition, what) CISAMR_CHECK(condition, what)
#endif
