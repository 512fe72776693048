// cisamr: the command line. Thin: parse, call the library, report. See DESIGN.md §6.
#include <unistd.h>

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
  app.set_version_flag("--version", std::string("cisamr 0.1.0"));
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
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return root ? app.exit(e) : app.exit(e, null_stream, null_stream);
  } catch (const CLI::CallForAllHelp& e) {
    return root ? app.exit(e) : app.exit(e, null_stream, null_stream);
  } catch (const CLI::CallForVersion& e) {
    return root ? app.exit(e) : app.exit(e, null_stream, null_stream);
  } catch (const CLI::ParseError& e) {
    return fail(2, std::string("cisamr: error: ") + e.what(), true);
  } catch (const InputError& e) {
    return fail(2, std::string("cisamr: error: ") + e.what(), parallel::is_collective(e));
  } catch (const MeshingError& e) {
    return fail(2, std::string("cisamr: error: ") + e.what(), parallel::is_collective(e));
  } catch (const std::exception& e) {
    return fail(1, std::string("cisamr: internal error: ") + e.what(), parallel::is_collective(e));
  }
  return exit_code;
}
