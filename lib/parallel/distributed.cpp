#include "parallel/distributed.hpp"

#include "pipeline/effective_levels.hpp"

#include <algorithm>
#include <chrono>
#include <regex>

#include "geometry/oracle2.hpp"
#include "io/scene_io.hpp"
#include "parallel/collective.hpp"
#include "parallel/exchange.hpp"

namespace cisamr::parallel {
namespace {

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// The subset oracle names inclusions by their index in the subset: name them as the scene does.
std::string rename_inclusions(const std::string& text, const std::vector<std::int32_t>& to_scene) {
  static const std::regex pattern(R"(inclusions\[(\d+)\])");
  std::string out;
  auto begin = std::sregex_iterator(text.begin(), text.end(), pattern);
  std::size_t last = 0;
  for (auto it = begin; it != std::sregex_iterator(); ++it) {
    const std::size_t local = std::stoul((*it)[1].str());
    out += text.substr(last, static_cast<std::size_t>(it->position()) - last);
    out += local < to_scene.size() ? "inclusions[" + std::to_string(to_scene[local]) + "]" : it->str();
    last = static_cast<std::size_t>(it->position() + it->length());
  }
  return out + text.substr(last);
}

struct Box {  // a partition as broadcast by rank 0
  std::int32_t id;
  std::int64_t lo[2], hi[2];
  double load;
};

}  // namespace

std::array<int, 2> partitions_of_rank(int partitions, int ranks, int rank) {
  const auto first = [&](int r) {
    return static_cast<int>(static_cast<std::int64_t>(partitions) * r / ranks);
  };
  return {first(rank), first(rank + 1)};
}

int rank_of_partition(int partition, int partitions, int ranks) {
  int r = static_cast<int>(static_cast<std::int64_t>(partition) * ranks / partitions);
  while (partitions_of_rank(partitions, ranks, r)[1] <= partition) ++r;
  while (partitions_of_rank(partitions, ranks, r)[0] > partition) --r;
  return r;
}

DistributedMesh2 mesh2_distributed(const Comm& comm, const std::string& scene_path, const MeshOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  geometry::SceneDesc scene;
  run_collectively(comm, [&] { scene = io::read_scene(scene_path); });
  const double read_seconds = seconds_since(start);
  DistributedMesh2 out = mesh2_distributed(comm, std::move(scene), options);
  out.times.add("read", read_seconds);
  return out;
}

DistributedMesh2 mesh2_distributed(const Comm& comm, geometry::SceneDesc scene, const MeshOptions& options) {
  DistributedMesh2 out;
  const int ranks = comm.size(), rank = comm.rank();
  const int n = options.partitions;
  out.times.add("read", 0);
  run_collectively(comm, [&] {
    if (scene.dimension != 2)
      throw InputError(scene.source, "dimension", "the parallel mesher is 2D only in this version");
    if (n < ranks)
      throw InputError("--partitions", "", std::to_string(n) + " partitions for " + std::to_string(ranks) +
                                               " MPI ranks: every rank needs at least one partition");
  });
  out.phases = scene.phases;
  out.domain = Box2{{scene.domain_min[0], scene.domain_min[1]}, {scene.domain_max[0], scene.domain_max[1]}};
  out.scene_inclusions = static_cast<std::int64_t>(scene.inclusions.size());

  // Partition on rank 0, broadcast the boxes.
  std::vector<Box> boxes;
  Bytes message;
  {
    ScopedPhase timer(&out.times, "partition");
    run_collectively(comm, [&] {
      if (rank != 0) return;
      const partition::Partition p = partition::partition_domain(scene, n, options.partitioning);
      Packer pack;
      pack.put_string(p.method);
      for (const auto& part : p.parts)
        pack.put(Box{part.id, {part.lattice_min[0], part.lattice_min[1]}, {part.lattice_max[0], part.lattice_max[1]}, part.load});
      message = pack.take();
    });
    message = broadcast_bytes(comm, message);
    run_collectively(comm, [&] {
      Unpacker u(message);
      out.partition_method = u.get_string();
      while (!u.done()) boxes.push_back(u.get<Box>());
      std::sort(boxes.begin(), boxes.end(), [](const Box& a, const Box& b) { return a.id < b.id; });
      if (static_cast<int>(boxes.size()) != n) throw std::logic_error("partition: wrong number of parts");
    });
  }

  // Ghost regions of this rank's partitions, and the inclusions they need.
  const auto [first, last] = partitions_of_rank(n, ranks, rank);
  grid::Lattice2 lattice;
  std::vector<int> levels;  // rule R1's level per scene inclusion
  std::vector<GhostRegion2> regions;
  {
    ScopedPhase timer(&out.times, "ghost");
    run_collectively(comm, [&] {
      lattice = scene_lattice2(scene, options.pipeline);
      // Every rank computes the same levels from the whole scene's descriptors (cheap:
      // pairs of nearby inclusions); they make SAMR local, so the ghost stays small.
      levels = pipeline::effective_levels2(scene, lattice);
      const InclusionIndex2 index(scene, lattice, options.ghost);
      for (int p = first; p < last; ++p) {
        grid::CellRange<2> box;
        for (int d = 0; d < 2; ++d) {
          box.lo[d] = boxes[static_cast<std::size_t>(p)].lo[d];
          box.hi[d] = boxes[static_cast<std::size_t>(p)].hi[d];
        }
        regions.push_back(ghost_region2(index, lattice, box, options.ghost));
        out.loaded_inclusions.insert(out.loaded_inclusions.end(), regions.back().inclusions.begin(),
                                     regions.back().inclusions.end());
      }
      std::sort(out.loaded_inclusions.begin(), out.loaded_inclusions.end());
      out.loaded_inclusions.erase(std::unique(out.loaded_inclusions.begin(), out.loaded_inclusions.end()),
                                  out.loaded_inclusions.end());
    });
  }

  // The descriptors this rank needs; the rest of the scene is dropped now.
  geometry::SceneDesc needed;
  run_collectively(comm, [&] {
    needed = subset_scene(scene, out.loaded_inclusions);
    std::vector<geometry::Inclusion>().swap(scene.inclusions);
  });

  // The unchanged sequential kernel on each partition, with an oracle built from exactly
  // that partition's inclusions: its output (order included) is then the same whatever
  // the other partitions of its rank, so the gathered file does not depend on the ranks.
  std::vector<PartitionOutput2> outputs;
  std::vector<PartitionSummary> mine;
  pipeline::Stats local;
  run_collectively(comm, [&] {
    for (int p = first; p < last; ++p) {
      const GhostRegion2& region = regions[static_cast<std::size_t>(p - first)];
      std::unique_ptr<geometry::Oracle2> oracle;
      {
        ScopedPhase timer(&out.times, "oracle");
        std::vector<std::int32_t> local_index;  // positions in `needed`
        for (std::int32_t k : region.inclusions)
          local_index.push_back(static_cast<std::int32_t>(
              std::lower_bound(out.loaded_inclusions.begin(), out.loaded_inclusions.end(), k) -
              out.loaded_inclusions.begin()));
        try {
          oracle = std::make_unique<geometry::Oracle2>(subset_scene(needed, local_index));
        } catch (const InputError& e) {
          throw InputError(e.file(), rename_inclusions(e.field(), region.inclusions),
                           rename_inclusions(e.problem(), region.inclusions));
        }
      }
      const auto t0 = std::chrono::steady_clock::now();
      std::vector<int> region_levels;
      for (std::int32_t k : region.inclusions) region_levels.push_back(levels[static_cast<std::size_t>(k)]);
      PartitionOutput2 o{p, region.box,
                         pipeline::run2(*oracle, lattice, region.box, region.ghost, options.pipeline, p, region_levels)};
      PartitionSummary s;
      s.id = p;
      s.rank = rank;
      s.kernel_seconds = seconds_since(t0);
      s.lattice_min = {region.box.lo[0], region.box.lo[1]};
      s.lattice_max = {region.box.hi[0], region.box.hi[1]};
      s.load = boxes[static_cast<std::size_t>(p)].load;
      s.ghost = region.ghost;
      s.ghost_cells = o.result.stats.coarse_cells - region.box.count(0) * region.box.count(1);
      s.inclusions = static_cast<std::int64_t>(region.inclusions.size());
      s.elements = static_cast<std::int64_t>(o.result.mesh.cell_count());
      s.nodes = static_cast<std::int64_t>(o.result.mesh.node_count());
      const pipeline::Stats& st = o.result.stats;
      for (const auto& [name, sec] : st.times.phases()) out.times.add(name, sec);
      local.coarse_cells += region.box.count(0) * region.box.count(1);
      local.leaves += st.leaves;
      local.refinements += st.refinements;
      local.lattice_nodes += st.lattice_nodes;
      local.snapped_nodes += st.snapped_nodes;
      local.cut_quads += st.cut_quads;
      local.double_diagonal += st.double_diagonal;
      local.hanging_cells += st.hanging_cells;
      local.unresolved += st.unresolved;
      local.collapsed += st.collapsed;
      local.max_collapse_deviation = std::max(local.max_collapse_deviation, st.max_collapse_deviation);
      if (st.min_collapse_level >= 0)
        local.min_collapse_level = local.min_collapse_level < 0 ? st.min_collapse_level
                                                                : std::min(local.min_collapse_level, st.min_collapse_level);
      mine.push_back(s);
      outputs.push_back(std::move(o));
    }
  });

  {
    ScopedPhase timer(&out.times, "merge");
    out.piece = merge_and_number2(comm, outputs, lattice);
  }
  out.global_cells = comm.allreduce_sum(static_cast<std::int64_t>(out.piece.mesh.cell_count()));

  // Counters over all ranks. (leaves/refinements/... count ghost work too: they say what
  // was computed, not what was kept.)
  pipeline::Stats& g = out.stats;
  g.coarse_cells = comm.allreduce_sum(local.coarse_cells);
  g.leaves = comm.allreduce_sum(local.leaves);
  g.refinements = comm.allreduce_sum(local.refinements);
  g.lattice_nodes = comm.allreduce_sum(local.lattice_nodes);
  g.snapped_nodes = comm.allreduce_sum(local.snapped_nodes);
  g.cut_quads = comm.allreduce_sum(local.cut_quads);
  g.double_diagonal = comm.allreduce_sum(local.double_diagonal);
  g.hanging_cells = comm.allreduce_sum(local.hanging_cells);
  g.unresolved = comm.allreduce_sum(local.unresolved);
  g.collapsed = comm.allreduce_sum(local.collapsed);
  g.max_collapse_deviation = comm.allreduce_max(local.max_collapse_deviation);
  const double coarsest = comm.allreduce_min(local.min_collapse_level < 0 ? 1e9 : double(local.min_collapse_level));
  g.min_collapse_level = coarsest >= 1e9 ? -1 : static_cast<int>(coarsest);
  g.max_level = lattice.max_level;

  // Every partition's summary on every rank.
  Packer p;
  p.put_vector(mine);
  for (const Bytes& b : allgather_bytes(comm, p.bytes())) {
    const auto v = Unpacker(b).get_vector<PartitionSummary>();
    out.partitions.insert(out.partitions.end(), v.begin(), v.end());
  }
  std::sort(out.partitions.begin(), out.partitions.end(),
            [](const PartitionSummary& a, const PartitionSummary& b) { return a.id < b.id; });
  return out;
}

}  // namespace cisamr::parallel
