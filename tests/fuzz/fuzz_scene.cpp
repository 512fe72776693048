// Scene JSON (cisamr-scene/1): io::parse_scene on the bytes. STL files named by the scene
// are neither probed nor read, so the input alone decides the outcome.
#include <string>

#include "fuzz/fuzz_target.hpp"
#include "io/scene_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  return cisamr::fuzz::expect_input_error_only([&] {
    cisamr::io::parse_scene(text, "fuzz.json", cisamr::io::ReadSceneOptions{false, false});
  });
}
