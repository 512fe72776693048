#pragma once
// What `cisamr mesh` prints after a run (mesh_summary.cpp): to `out` the summary line (output
// path, counts, worst aspect ratio against the bound, time; ranks and partitions in a
// parallel run) and the collapse note unless --quiet, with --verbose the phase timings and
// the partitions; to stderr the warning about cells below the finest resolution.
#include <cstdio>

#include "commands.hpp"
#include "driver/driver.hpp"

namespace cisamr::app {

template <int Dim>
void print_mesh_summary(std::FILE* out, const driver::MeshRun<Dim>& run, const driver::Output& output,
                        const GlobalFlags& flags);

}  // namespace cisamr::app
