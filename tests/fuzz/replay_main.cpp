// The fuzz targets without libFuzzer: runs every file of the given corpus directories and
// a fixed number of seeded mutations of each (bit flips, truncations, inserted bytes,
// interesting integers in binary and as text, duplicated and deleted chunks) through
// LLVMFuzzerTestOneInput, in process. The mutations depend only on the corpus and the seed,
// so a failure reproduces. Anything that escapes the target (an exception other than
// InputError) is reported with the input, saved as replay-failure-<n> in the working
// directory, and fails the run.
//
//   replay [--mutations N] [--seed S] DIR_OR_FILE...
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <typeinfo>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace {

using Bytes = std::string;

// splitmix64: the same sequence everywhere (std:: distributions are not portable).
struct Random {
  std::uint64_t state;
  std::uint64_t next() {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  std::size_t below(std::size_t n) { return n == 0 ? 0 : static_cast<std::size_t>(next() % n); }
};

const char* const kTextNumbers[] = {"0", "-1", "1", "2", "3", "4", "10", "1e400", "-1e400", "nan", "inf",
                                    "18446744073709551615", "18446744073709551616", "99999999999999999999",
                                    "-9223372036854775808", "9223372036854775807", "4294967296", "2147483648",
                                    "1e18", "1e-320", "0.5", "", "x", "+", "-"};
const char* const kTokens[] = {"[", "]", "{", "}", "\"", ",", ":", "\n", " ", "\xff", "\xc3", "\x01", "<",
                               ">", "/>", "=", "$", "*", "#", "_", "solid", "endsolid", "facet", "\\u0000"};
const std::uint64_t kBinaryNumbers[] = {0, 1, 0x7f, 0x80, 0xff, 0x7fff, 0x8000, 0xffff, 0x7fffffff,
                                        0x80000000, 0xffffffff, 0x7fffffffffffffffull,
                                        0x8000000000000000ull, 0xffffffffffffffffull,
                                        0xfffffffffffffff0ull, 0x100000000ull};

void mutate_once(Bytes& b, Random& r) {
  switch (r.below(8)) {
    case 0:  // flip a bit
      if (!b.empty()) b[r.below(b.size())] ^= static_cast<char>(1u << r.below(8));
      break;
    case 1:  // truncate
      b.resize(r.below(b.size() + 1));
      break;
    case 2:  // insert random bytes
      b.insert(r.below(b.size() + 1), Bytes(1 + r.below(4), static_cast<char>(r.next())));
      break;
    case 3: {  // an interesting integer, little endian, over 1, 2, 4 or 8 bytes
      const std::size_t width = std::size_t{1} << r.below(4);
      if (b.size() < width) break;
      const std::uint64_t v = kBinaryNumbers[r.below(std::size(kBinaryNumbers))];
      std::memcpy(&b[r.below(b.size() - width + 1)], &v, width);
      break;
    }
    case 4: {  // a number written as text replaced by an interesting one
      std::size_t at = r.below(b.size() + 1);
      while (at < b.size() && !(b[at] >= '0' && b[at] <= '9')) ++at;
      std::size_t end = at;
      while (end < b.size() && std::strchr("0123456789.eE+-", b[end]) && b[end] != '\0') ++end;
      b.replace(at, end - at, kTextNumbers[r.below(std::size(kTextNumbers))]);
      break;
    }
    case 5: {  // duplicate a chunk somewhere
      if (b.empty()) break;
      const std::size_t from = r.below(b.size()), length = 1 + r.below(std::min<std::size_t>(b.size() - from, 256));
      const Bytes chunk = b.substr(from, length);
      b.insert(r.below(b.size() + 1), chunk);
      break;
    }
    case 6: {  // delete a chunk
      if (b.empty()) break;
      const std::size_t from = r.below(b.size());
      b.erase(from, 1 + r.below(std::min<std::size_t>(b.size() - from, 64)));
      break;
    }
    default:  // insert a token that matters to one of the formats
      b.insert(r.below(b.size() + 1), kTokens[r.below(std::size(kTokens))]);
      break;
  }
}

std::vector<std::filesystem::path> inputs(const std::vector<std::string>& roots) {
  std::vector<std::filesystem::path> files;
  for (const auto& root : roots) {
    if (std::filesystem::is_directory(root)) {
      for (const auto& e : std::filesystem::recursive_directory_iterator(root))
        if (e.is_regular_file()) files.push_back(e.path());
    } else {
      files.emplace_back(root);
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

int failures = 0;

void run(const Bytes& input, const std::string& what) {
  try {
    LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(input.data()), input.size());
  } catch (const std::exception& e) {
    const std::string saved = "replay-failure-" + std::to_string(failures++);
    std::ofstream(saved, std::ios::binary) << input;
    std::fprintf(stderr, "FAIL %s: %s escaped: %s (input saved as %s)\n", what.c_str(),
                 typeid(e).name(), e.what(), saved.c_str());
  } catch (...) {
    const std::string saved = "replay-failure-" + std::to_string(failures++);
    std::ofstream(saved, std::ios::binary) << input;
    std::fprintf(stderr, "FAIL %s: a non-std exception escaped (input saved as %s)\n", what.c_str(),
                 saved.c_str());
  }
}

}  // namespace

int main(int argc, char** argv) {
  long mutations = 200;
  std::uint64_t seed = 1;
  std::vector<std::string> roots;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--mutations" && i + 1 < argc) mutations = std::stol(argv[++i]);
    else if (a == "--seed" && i + 1 < argc) seed = std::stoull(argv[++i]);
    else roots.push_back(a);
  }
  const auto files = inputs(roots);
  if (files.empty()) {
    std::fprintf(stderr, "replay: no inputs (usage: replay [--mutations N] [--seed S] DIR_OR_FILE...)\n");
    return 2;
  }
  long executions = 0;
  for (std::size_t f = 0; f < files.size(); ++f) {
    std::ifstream in(files[f], std::ios::binary);
    const Bytes original((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    run(original, files[f].string());
    ++executions;
    for (long m = 0; m < mutations; ++m) {
      Random r{seed * 0x100000001B3ull + f * 1000003ull + static_cast<std::uint64_t>(m)};
      Bytes b = original;
      for (std::size_t k = 1 + r.below(3); k > 0; --k) mutate_once(b, r);
      run(b, files[f].string() + " mutation " + std::to_string(m));
      ++executions;
    }
  }
  std::printf("replay: %ld executions from %zu files, %d failures\n", executions, files.size(), failures);
  return failures == 0 ? 0 : 1;
}
