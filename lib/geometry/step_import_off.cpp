// import_step without OpenCASCADE (CISAMR_WITH_OCCT=OFF): refuses every file.
#include "geometry/step_import.hpp"

namespace cisamr::geometry {

bool step_import_available() { return false; }

std::string import_step(std::string_view, const std::string&, BrepData& out) {
  out = BrepData{};
  return "step: this cisamr was built with CISAMR_WITH_OCCT=OFF";
}

}  // namespace cisamr::geometry
