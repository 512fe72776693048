// pack_bench SPEC [-o SCENE] [--partition N1,N2,...]: packs a spec, prints the report and
// the wall time, optionally writes the scene and compares Algorithm 1 with a uniform grid.
#include <chrono>
#include <cstdio>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "io/scene_io.hpp"
#include "pack/pack.hpp"
#include "partition/partition.hpp"

using namespace cisamr;

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: pack_bench SPEC [-o SCENE] [--partition N1,N2,...]\n");
    return 2;
  }
  std::string spec_path = argv[1], out;
  std::vector<int> parts;
  for (int i = 2; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "-o")) out = argv[i + 1];
    if (!std::strcmp(argv[i], "--partition")) {
      std::stringstream s(argv[i + 1]);
      std::string tok;
      while (std::getline(s, tok, ',')) parts.push_back(std::stoi(tok));
    }
  }
  try {
    const auto t0 = std::chrono::steady_clock::now();
    const pack::PackSpec spec = pack::read_pack_spec(spec_path);
    const pack::PackResult r = pack::pack(spec);
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("%s: %zu inclusions, total fraction %.4f, pack %.3f s (incl. spec reading %.3f s)\n", spec_path.c_str(),
                r.scene.inclusions.size(), r.report.total_fraction, r.report.seconds, t);
    for (const auto& p : r.report.populations)
      std::printf("  %-12s placed %lld fraction %.4f%s size min/mean/max/std %.3g/%.3g/%.3g/%.3g trials %lld failed %lld\n",
                  p.name.c_str(), (long long)p.placed, p.achieved_fraction, p.fraction_is_estimate ? " (raster)" : "",
                  p.size_min, p.size_mean, p.size_max, p.size_std, (long long)p.trials, (long long)p.failures);
    std::printf("  exact checks %lld, cleared by secondary boxes %lld\n", (long long)r.report.exact_checks,
                (long long)r.report.secondary_rejections);
    if (!out.empty()) io::write_scene(out, r.scene);
    if (!parts.empty()) {
      std::printf("  %6s | %-28s | %-28s | %-28s\n", "N", "ours (cisamr partition)", "merging only (pure Alg. 1)", "uniform grid");
      std::printf("  %6s | %9s %18s | %9s %18s | %9s %18s\n", "", "max/mean", "shared faces", "max/mean", "shared faces",
                  "max/mean", "shared faces");
      for (int n : parts) {
        const auto a = std::chrono::steady_clock::now();
        const auto ours = partition::partition_domain(r.scene, n);
        const double ta = std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count();
        partition::PartitionOptions plain;
        plain.rebalance = false;
        plain.method = partition::PartitionOptions::Method::merge;
        const auto alg1 = partition::partition_domain(r.scene, n, plain);
        const auto uni = partition::uniform_grid_partition(r.scene, n);
        std::printf("  %6d | %9.4f %18.6g | %9.4f %18.6g | %9.4f %18.6g   (max load %.6g vs uniform %.6g; %s; %.3f s)\n", n,
                    ours.imbalance(), ours.shared_face_measure(), alg1.imbalance(), alg1.shared_face_measure(),
                    uni.imbalance(), uni.shared_face_measure(), ours.max_load(), uni.max_load(), ours.method.c_str(), ta);
      }
    }
  } catch (const InputError& e) {
    std::fprintf(stderr, "pack_bench: error: %s\n", e.what());
    return 2;
  }
  return 0;
}
