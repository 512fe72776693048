#pragma once
// STEP import through OpenCASCADE 7.6 (docs/nurbs-step-design.md §3.2), the only code of
// cisamr that sees OCCT (step_import.cpp; step_import_off.cpp when built with
// CISAMR_WITH_OCCT=OFF). Geometry never opens files: the caller passes the bytes.
#include <string>
#include <string_view>

#include "geometry/brep_data.hpp"

namespace cisamr::geometry {

// Whether this build reads STEP files (CISAMR_WITH_OCCT).
bool step_import_available();

// Reads the STEP file `bytes` (named `name` in messages) into `out`: every solid, its
// faces converted to B-spline surfaces with their uv loops, meshed, with its volume and
// box. Returns "" or the problem in one line starting with `name` ("parts.step: no
// solid"; "parts.step: entity #831 (ADVANCED_FACE): …"; "parts.step: solid 1: open shell
// (4 free edges)"). Deterministic: the same bytes give the same `out`, bit for bit.
// Thread-safe (imports are serialised: OCCT's settings are global). `out` is replaced.
std::string import_step(std::string_view bytes, const std::string& name, BrepData& out);

}  // namespace cisamr::geometry
