// cisamr: the command line. Thin: parse, call the library, report. See DESIGN.md §6.
#include <unistd.h>

#include <cstdio>
#include <exception>
#include <string>

#include "commands.hpp"
#include "core/error.hpp"

namespace cisamr::app {
bool show_progress(const GlobalFlags& flags) { return !flags.quiet && isatty(STDERR_FILENO); }
}  // namespace cisamr::app

int main(int argc, char** argv) {
  using namespace cisamr;
  CLI::App app{"cisamr: conforming meshes of heterogeneous microstructures (CISAMR)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("cisamr 0.1.0"));
  app::GlobalFlags flags;
  int exit_code = 0;
  app::add_mesh_command(app, flags, exit_code);
  app::add_certify_command(app, flags, exit_code);
  app::add_pack_command(app, flags, exit_code);
  app::add_partition_command(app, flags, exit_code);
  for (CLI::App* sub : app.get_subcommands({})) {
    sub->add_flag("-q,--quiet", flags.quiet, "No progress output");
    sub->add_flag("-v,--verbose", flags.verbose, "Print phase timings");
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "cisamr: error: %s\n", e.what());
    return 2;
  } catch (const InputError& e) {
    std::fprintf(stderr, "cisamr: error: %s\n", e.what());
    return 2;
  } catch (const MeshingError& e) {
    std::fprintf(stderr, "cisamr: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cisamr: internal error: %s\n", e.what());
    return 1;
  }
  return exit_code;
}
