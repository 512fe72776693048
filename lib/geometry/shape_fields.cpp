#include "geometry/shape_fields.hpp"

#include <charconv>

namespace cisamr::geometry {

std::string number_text(double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

bool is_identity(const Rotation3& r) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (r[i][j] != (i == j ? 1.0 : 0.0)) return false;
  return true;
}

}  // namespace cisamr::geometry
