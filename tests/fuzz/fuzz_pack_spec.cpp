// Pack spec JSON (cisamr-pack/1): pack::parse_pack_spec on the bytes.
#include <string>

#include "fuzz/fuzz_target.hpp"
#include "pack/pack.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  return cisamr::fuzz::expect_input_error_only(
      [&] { cisamr::pack::parse_pack_spec(text, "fuzz.pack.json"); });
}
