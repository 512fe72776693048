#pragma once
// Each subcommand lives in its own cmd_<name>.cpp and registers itself on the CLI11 app.
// The callback stores the process exit code in `exit_code`; errors are thrown
// (InputError → exit 2, anything else → exit 1) and printed once by main().
#include <CLI/CLI.hpp>
#include <string>
#include <string_view>

#include "io/atomic_file.hpp"

namespace cisamr::app {

struct GlobalFlags {
  bool quiet = false;    // no progress output
  bool verbose = false;  // phase timings
  double progress_interval = 5;  // seconds between progress lines when stderr is not a terminal
};

void add_mesh_command(CLI::App& app, GlobalFlags& flags, int& exit_code);
void add_certify_command(CLI::App& app, GlobalFlags& flags, int& exit_code);
void add_pack_command(CLI::App& app, GlobalFlags& flags, int& exit_code);
void add_partition_command(CLI::App& app, GlobalFlags& flags, int& exit_code);
void add_compare_command(CLI::App& app, GlobalFlags& flags, int& exit_code);  // 3D, vs TetGen

// Progress lines go to stderr only when it is a terminal and --quiet is not given.
bool show_progress(const GlobalFlags& flags);

// Checks of option values (options.cpp). CLI11 prefixes the option's name: "--bound: must
// be a number in [1, 1e+06] (got nan)". `number_in`: a finite number in [lo, hi], a whole
// one where `whole`; `output_path`: not empty ("--output: an empty path: ...").
CLI::Validator number_in(double lo, double hi, bool whole = false);
// A hidden option (group "") has no name in CLI11's messages (": must be ..."): `named`
// puts it back ("--ghost-cubes: must be ..."; main drops the empty prefix).
CLI::Validator named(const std::string& option, CLI::Validator check);
CLI::Validator output_path();

// Writes a report file whole (io::AtomicFile: it appears complete or not at all).
inline void write_text_file(const std::string& path, std::string_view text) {
  io::AtomicFile file(path);
  file.write(text);
  file.commit();
}

}  // namespace cisamr::app
