// STL surfaces, ASCII and binary (the reader tells them apart by the size): io::read_stl.
#include "fuzz/fuzz_target.hpp"
#include "io/stl_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const cisamr::fuzz::ScratchFile file(".stl");
  const std::string& path = file.write(data, size);
  return cisamr::fuzz::expect_input_error_only([&] { cisamr::io::read_stl(path); });
}
