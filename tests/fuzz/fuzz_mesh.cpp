// One mesh reader of `cisamr certify`: io::read_mesh on a file whose extension
// (CISAMR_FUZZ_MESH_EXTENSION: ".vtu", ".msh", ".inp" or ".mesh") picks the reader.
#include "fuzz/fuzz_target.hpp"
#include "io/mesh_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const cisamr::fuzz::ScratchFile file(CISAMR_FUZZ_MESH_EXTENSION);
  const std::string& path = file.write(data, size);
  return cisamr::fuzz::expect_input_error_only([&] { cisamr::io::read_mesh(path); });
}
