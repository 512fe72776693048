// cisamr: the command line. Thin: parse, call the library, report. See DESIGN.md §6.
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <exception>
#include <ostream>
#include <streambuf>
#include <string>

#include "commands.hpp"
#include "core/error.hpp"
#include "io/atomic_file.hpp"
#include "parallel/collective.hpp"
#include "parallel/session.hpp"

namespace cisamr::app {
bool show_progress(const GlobalFlags& flags) { return !flags.quiet && isatty(STDERR_FILENO); }
}  // namespace cisamr::app

namespace {

constexpr const char* kVersion = "cisamr 0.1.0";

CLI::App* find_command(CLI::App& app, const std::string& name) {
  for (CLI::App* sub : app.get_subcommands({}))
    if (sub->get_name() == name) return sub;
  return nullptr;
}

// The commands, one line each, and where to learn more.
std::string command_list(CLI::App& app) {
  std::string text = "usage: cisamr COMMAND [OPTIONS]   (cisamr --version)\ncommands:\n";
  for (CLI::App* sub : app.get_subcommands({})) {
    std::string name = sub->get_name();
    name.resize(std::max<std::size_t>(name.size(), 11), ' ');
    text += "  " + name + sub->get_description() + "\n";
  }
  return text + "`cisamr COMMAND --help` (or `cisamr help COMMAND`) lists a command's options\n";
}

int unknown_command(CLI::App& app, const std::string& name, bool root) {
  if (root) std::fprintf(stderr, "cisamr: error: unknown command '%s'\n%s", name.c_str(), command_list(app).c_str());
  return 2;
}

// Swallows what ranks other than 0 would print (help, version).
class NullBuffer : public std::streambuf {
 protected:
  int overflow(int c) override { return c; }
};

}  // namespace

int main(int argc, char** argv) {
  using namespace cisamr;
  // MPI starts only when mpiexec launched us; a plain run never touches it.
  parallel::MpiSession session(argc, argv);
  const Comm& comm = session.comm();
  // A run stopped by SIGINT/SIGTERM (under mpiexec: every rank gets it) leaves no
  // half-written temporary beside its outputs.
  io::install_signal_cleanup();
  const bool root = comm.rank() == 0;
  NullBuffer null_buffer;
  std::ostream null_stream(&null_buffer);
  // An error every rank has (argv is the same everywhere; lib/parallel agrees on the
  // others) is printed once, on rank 0, and every rank ends normally with `code`. An error
  // only this rank has ends the whole job at once, so nobody waits for it.
  const auto fail = [&](int code, const std::string& line, bool on_every_rank) {
    if (on_every_rank || comm.size() == 1) {
      if (root) std::fprintf(stderr, "%s\n", line.c_str());
      return code;
    }
    std::fprintf(stderr, "%s (rank %d)\n", line.c_str(), comm.rank());
    std::fflush(stderr);
    session.abort(code);
  };
  CLI::App app{"cisamr: conforming meshes of heterogeneous microstructures (CISAMR)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", kVersion);
  app::GlobalFlags flags;
  int exit_code = 0;
  app::add_mesh_command(app, flags, exit_code);
  app::add_certify_command(app, flags, exit_code);
  app::add_pack_command(app, flags, exit_code);
  app::add_partition_command(app, flags, exit_code);
  app::add_compare_command(app, flags, exit_code);
  for (CLI::App* sub : app.get_subcommands({})) {
    sub->add_flag("-q,--quiet", flags.quiet, "No progress output");
    sub->add_flag("-v,--verbose", flags.verbose, "Print phase timings");
    sub->add_option("--progress-interval", flags.progress_interval,
                    "Seconds between progress lines when stderr is not a terminal (a log, mpiexec; 0: every phase)")
        ->check(app::number_in(0, 86400))
        ->capture_default_str();
    sub->set_version_flag("--version", kVersion);
  }
  // `cisamr`, `cisamr help [COMMAND]` and an unknown command: what exists, before CLI11,
  // which would only say that a subcommand is required.
  const std::string first = argc > 1 ? argv[1] : "";
  if (argc == 1 || first == "help") {
    CLI::App* about = argc > 2 ? find_command(app, argv[2]) : nullptr;
    if (argc > 2 && about == nullptr) return unknown_command(app, argv[2], root);
    if (root) std::fputs((about != nullptr ? about->help() : command_list(app)).c_str(), argc == 1 ? stderr : stdout);
    return argc == 1 ? 2 : 0;
  }
  if (!first.empty() && first[0] != '-' && find_command(app, first) == nullptr) return unknown_command(app, first, root);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return root ? app.exit(e) : app.exit(e, null_stream, null_stream);
  } catch (const CLI::CallForAllHelp& e) {
    return root ? app.exit(e) : app.exit(e, null_stream, null_stream);
  } catch (const CLI::CallForVersion& e) {
    return root ? app.exit(e) : app.exit(e, null_stream, null_stream);
  } catch (const CLI::ParseError& e) {
    std::string what = e.what();
    if (what.starts_with(": ")) what.erase(0, 2);  // a hidden option's empty name (commands.hpp, named)
    return fail(2, "cisamr: error: " + what, true);
  } catch (const InputError& e) {
    return fail(2, std::string("cisamr: error: ") + e.what(), parallel::is_collective(e));
  } catch (const MeshingError& e) {
    return fail(2, std::string("cisamr: error: ") + e.what(), parallel::is_collective(e));
  } catch (const std::exception& e) {
    return fail(1, std::string("cisamr: internal error: ") + e.what(), parallel::is_collective(e));
  }
  return exit_code;
}
