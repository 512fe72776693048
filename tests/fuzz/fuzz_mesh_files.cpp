// The mesh readers that read several files: io::read_mesh on the first of
// CISAMR_FUZZ_MESH_FILES (a comma-separated list of names, e.g. "mesh.pvtu,piece0.vtu,
// piece1.vtu" or "mesh.ele,mesh.node"), each file one part of the input (fuzz_target.hpp).
#include <sstream>

#include "fuzz/fuzz_target.hpp"
#include "io/mesh_io.hpp"

namespace {
std::vector<std::string> file_names() {
  std::vector<std::string> names;
  std::stringstream list(CISAMR_FUZZ_MESH_FILES);
  for (std::string name; std::getline(list, name, ',');) names.push_back(name);
  return names;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const cisamr::fuzz::ScratchFolder folder(file_names());
  const std::string path = folder.write(data, size);
  return cisamr::fuzz::expect_input_error_only([&] { cisamr::io::read_mesh(path); });
}
