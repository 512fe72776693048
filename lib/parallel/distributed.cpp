#include "parallel/distributed.hpp"

#include <algorithm>
#include <chrono>
#include <map>
#include <regex>

#include "geometry/oracle.hpp"
#include "geometry/shapes.hpp"
#include "io/scene_io.hpp"
#include "parallel/collective.hpp"
#include "parallel/exchange.hpp"
#include "pipeline/effective_levels.hpp"

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

}  // namespace

// Not in the anonymous namespace: the exported templates' lambdas capture them.
namespace distributed_detail {
struct Box {  // a partition as broadcast by rank 0
  std::int32_t id;
  std::int64_t lo[3], hi[3];
  double load;
};

struct StlBox {  // an STL surface's bounding box, as the rank that read it computed it
  std::int32_t inclusion;
  Box3 box;
};
}  // namespace distributed_detail
using distributed_detail::Box;
using distributed_detail::StlBox;

namespace {

std::vector<std::int32_t> stl_inclusions(const geometry::SceneDesc& scene) {
  std::vector<std::int32_t> out;
  for (std::size_t k = 0; k < scene.inclusions.size(); ++k)
    if (const auto* s = std::get_if<geometry::StlSurface>(&scene.inclusions[k].shape); s && s->triangles.empty())
      out.push_back(static_cast<std::int32_t>(k));
  return out;
}

}  // namespace

StlShares share_stl_surfaces(const Comm& comm, geometry::SceneDesc& scene, const partition::PartitionOptions& popt,
                             bool loads_needed) {
  StlShares out;
  const int ranks = comm.size(), rank = comm.rank();
  const std::size_t n = scene.inclusions.size();
  out.known.resize(n);
  const std::vector<std::int32_t> unread = stl_inclusions(scene);
  std::vector<int> owner(n, -1);  // the rank that reads inclusion k's file
  {
    std::map<std::string, int> file_rank;
    for (std::int32_t k : unread) {
      const auto& file = std::get<geometry::StlSurface>(scene.inclusions[static_cast<std::size_t>(k)].shape).file;
      const auto [it, inserted] = file_rank.try_emplace(file, static_cast<int>(file_rank.size()) % ranks);
      owner[static_cast<std::size_t>(k)] = it->second;
    }
  }
  std::vector<std::int32_t> mine;
  for (std::int32_t k : unread)
    if (owner[static_cast<std::size_t>(k)] == rank) mine.push_back(k);

  Packer boxes, loads;
  run_collectively(comm, [&] {
    out.files_read += io::load_stl_surfaces(scene, mine, &out.cache);
    std::vector<StlBox> b;
    for (std::int32_t k : mine) {
      const geometry::Inclusion& inc = scene.inclusions[static_cast<std::size_t>(k)];
      b.push_back({k, geometry::shape_bounding_box(inc.shape)});
      if (!loads_needed) continue;
      const partition::InclusionLoad load = partition::stl_surface_load(scene, k, popt);
      loads.put<std::int32_t>(k);
      loads.put_vector(load.cells);
      loads.put_vector(load.loads);
      loads.put(load.box);
    }
    boxes.put_vector(b);
  });
  for (const Bytes& bytes : allgather_bytes(comm, boxes.bytes()))
    for (const StlBox& b : Unpacker(bytes).get_vector<StlBox>()) out.known[static_cast<std::size_t>(b.inclusion)] = b.box;
  if (loads_needed) {
    out.loads.resize(n);
    for (const Bytes& bytes : gather_bytes(comm, loads.take())) {
      Unpacker u(bytes);
      while (!u.done()) {
        const auto k = static_cast<std::size_t>(u.get<std::int32_t>());
        out.loads[k].cells = u.get_vector<std::int64_t>();
        out.loads[k].loads = u.get_vector<double>();
        out.loads[k].box = u.get<Box3>();
      }
    }
  }

  // The sweep of pipeline::surface_unions, on the same boxes.
  Packer pairs;
  run_collectively(comm, [&] {
    const std::vector<Box3> box = pipeline::holding_boxes(scene, out.known);
    std::vector<pipeline::SurfacePair> found;
    std::int64_t candidate = 0;
    for (const pipeline::SurfacePair& p : pipeline::surface_union_candidates(scene, box)) {
      // Who decides: the reader of the first unread STL member, else ranks in turn.
      int decider = static_cast<int>(candidate++ % ranks);
      for (const std::int32_t k : {p.a, p.b})
        if (owner[static_cast<std::size_t>(k)] >= 0) {
          decider = owner[static_cast<std::size_t>(k)];
          break;
        }
      if (decider != rank) continue;
      const std::array<std::int32_t, 2> both{p.a, p.b};
      out.files_read += io::load_stl_surfaces(scene, both, &out.cache);
      if (geometry::shapes_overlap(scene.inclusions[static_cast<std::size_t>(p.a)].shape,
                                   scene.inclusions[static_cast<std::size_t>(p.b)].shape, 0))
        found.push_back(p);
    }
    pairs.put_vector(found);
  });
  for (const Bytes& bytes : allgather_bytes(comm, pairs.bytes())) {
    const auto v = Unpacker(bytes).get_vector<pipeline::SurfacePair>();
    out.unions.insert(out.unions.end(), v.begin(), v.end());
  }
  std::sort(out.unions.begin(), out.unions.end());
  // Triangles stay in the cache only (for the partitions that need them later).
  for (std::int32_t k : unread)
    std::get<geometry::StlSurface>(scene.inclusions[static_cast<std::size_t>(k)].shape).triangles.clear();
  return out;
}

namespace {

// The dimension's kernel and counters.
pipeline::Result2 run_kernel(const geometry::Oracle2& oracle, const grid::Lattice2& lattice,
                             const GhostRegion2& region, const pipeline::Options& options, int partition,
                             std::span<const int> levels) {
  return pipeline::run2(oracle, lattice, region.box, region.ghost, options, partition, levels);
}
pipeline::Result3 run_kernel(const geometry::Oracle3& oracle, const grid::Lattice3& lattice,
                             const GhostRegion3& region, const pipeline::Options& options, int partition,
                             std::span<const int> levels) {
  return pipeline::run3(oracle, lattice, region.box, region.ghost, options, partition, levels);
}
std::int64_t coarse_cells_of(const pipeline::Stats& s) { return s.coarse_cells; }
std::int64_t coarse_cells_of(const pipeline::Stats3& s) { return s.coarse_cubes; }

// Counters of one partition into this rank's sum (box cells only: ghost work is in leaves).
void accumulate(pipeline::Stats& sum, const pipeline::Stats& st, std::int64_t box_cells) {
  sum.coarse_cells += box_cells;
  sum.leaves += st.leaves;
  sum.refinements += st.refinements;
  sum.lattice_nodes += st.lattice_nodes;
  sum.snapped_nodes += st.snapped_nodes;
  sum.cut_quads += st.cut_quads;
  sum.double_diagonal += st.double_diagonal;
  sum.hanging_cells += st.hanging_cells;
  sum.unresolved += st.unresolved;
  sum.collapsed += st.collapsed;
  sum.max_collapse_deviation = std::max(sum.max_collapse_deviation, st.max_collapse_deviation);
  if (st.min_collapse_level >= 0)
    sum.min_collapse_level =
        sum.min_collapse_level < 0 ? st.min_collapse_level : std::min(sum.min_collapse_level, st.min_collapse_level);
}
void accumulate(pipeline::Stats3& sum, const pipeline::Stats3& st, std::int64_t box_cells) {
  sum.coarse_cubes += box_cells;
  sum.leaves += st.leaves;
  sum.refinements += st.refinements;
  sum.samr_sweeps = std::max(sum.samr_sweeps, st.samr_sweeps);
  sum.lattice_nodes += st.lattice_nodes;
  sum.snapped_nodes += st.snapped_nodes;
  sum.cut_tets += st.cut_tets;
  sum.cut_nodes += st.cut_nodes;
  sum.closed_tets += st.closed_tets;
  sum.steiner_points += st.steiner_points;
  sum.unresolved += st.unresolved;
  sum.inverted += st.inverted;
  sum.missing_crossings += st.missing_crossings;
  sum.worst_closure = std::max(sum.worst_closure, st.worst_closure);
  sum.worst_kept = std::max(sum.worst_kept, st.worst_kept);
  sum.worst_split = std::max(sum.worst_split, st.worst_split);
  sum.kept_above_5 += st.kept_above_5;
  sum.split_above_5 += st.split_above_5;
  sum.worst_swapped = std::max(sum.worst_swapped, st.worst_swapped);
  sum.face_swaps += st.face_swaps;
  sum.refused_nodes += st.refused_nodes;
  sum.collapsed_nodes += st.collapsed_nodes;
  sum.collapsed_cut_points += st.collapsed_cut_points;
  sum.max_collapse_deviation = std::max(sum.max_collapse_deviation, st.max_collapse_deviation);
  sum.guarded_leaves += st.guarded_leaves;
  sum.guard_combinations += st.guard_combinations;
  sum.max_level = std::max(sum.max_level, st.max_level);
}

// Sums (maxima) over ranks.
pipeline::Stats reduce(const Comm& comm, const pipeline::Stats& local) {
  pipeline::Stats g;
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
  return g;
}
pipeline::Stats3 reduce(const Comm& comm, const pipeline::Stats3& local) {
  pipeline::Stats3 g;
  g.coarse_cubes = comm.allreduce_sum(local.coarse_cubes);
  g.leaves = comm.allreduce_sum(local.leaves);
  g.refinements = comm.allreduce_sum(local.refinements);
  g.samr_sweeps = static_cast<int>(comm.allreduce_max(std::int64_t{local.samr_sweeps}));
  g.lattice_nodes = comm.allreduce_sum(local.lattice_nodes);
  g.snapped_nodes = comm.allreduce_sum(local.snapped_nodes);
  g.cut_tets = comm.allreduce_sum(local.cut_tets);
  g.cut_nodes = comm.allreduce_sum(local.cut_nodes);
  g.closed_tets = comm.allreduce_sum(local.closed_tets);
  g.steiner_points = comm.allreduce_sum(local.steiner_points);
  g.unresolved = comm.allreduce_sum(local.unresolved);
  g.inverted = comm.allreduce_sum(local.inverted);
  g.missing_crossings = comm.allreduce_sum(local.missing_crossings);
  g.worst_closure = comm.allreduce_max(local.worst_closure);
  g.worst_kept = comm.allreduce_max(local.worst_kept);
  g.worst_split = comm.allreduce_max(local.worst_split);
  g.kept_above_5 = comm.allreduce_sum(local.kept_above_5);
  g.split_above_5 = comm.allreduce_sum(local.split_above_5);
  g.worst_swapped = comm.allreduce_max(local.worst_swapped);
  g.face_swaps = comm.allreduce_sum(local.face_swaps);
  g.refused_nodes = comm.allreduce_sum(local.refused_nodes);
  g.collapsed_nodes = comm.allreduce_sum(local.collapsed_nodes);
  g.collapsed_cut_points = comm.allreduce_sum(local.collapsed_cut_points);
  g.max_collapse_deviation = comm.allreduce_max(local.max_collapse_deviation);
  g.guarded_leaves = comm.allreduce_sum(local.guarded_leaves);
  g.guard_combinations = comm.allreduce_sum(local.guard_combinations);
  g.max_level = static_cast<int>(comm.allreduce_max(std::int64_t{local.max_level}));
  return g;
}

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

template <int Dim>
DistributedMesh<Dim> mesh_distributed(const Comm& comm, const std::string& scene_path, const MeshOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  geometry::SceneDesc scene;
  // STL triangles are read later, only where needed (README.md, "Reading the scene").
  run_collectively(comm, [&] { scene = io::read_scene(scene_path, io::ReadSceneOptions{.load_stl = false, .probe_stl = false}); });
  const double read_seconds = seconds_since(start);
  DistributedMesh<Dim> out = mesh_distributed<Dim>(comm, std::move(scene), options);
  out.times.add("read", read_seconds);
  return out;
}

template <int Dim>
DistributedMesh<Dim> mesh_distributed(const Comm& comm, geometry::SceneDesc scene, const MeshOptions& options) {
  using Oracle = std::conditional_t<Dim == 2, geometry::Oracle2, geometry::Oracle3>;
  DistributedMesh<Dim> out;
  const int ranks = comm.size(), rank = comm.rank();
  const int n = options.partitions;
  out.times.add("read", 0);
  run_collectively(comm, [&] {
    if (scene.dimension != Dim)
      throw InputError(scene.source, "dimension",
                       "a " + std::to_string(scene.dimension) + "D scene given to the " + std::to_string(Dim) +
                           "D parallel mesher");
    if (n < ranks)
      throw InputError("--partitions", "", std::to_string(n) + " partitions for " + std::to_string(ranks) +
                                               " MPI ranks: every rank needs at least one partition");
  });
  out.phases = scene.phases;
  for (int d = 0; d < Dim; ++d) out.domain.min[d] = scene.domain_min[d], out.domain.max[d] = scene.domain_max[d];
  out.scene_inclusions = static_cast<std::int64_t>(scene.inclusions.size());

  // STL surfaces: each file read by one rank, boxes, loads and same-phase unions shared.
  StlShares stl;
  {
    ScopedPhase timer(&out.times, "read");
    if constexpr (Dim == 3) stl = share_stl_surfaces(comm, scene, options.partitioning, true);
    else stl.known.resize(scene.inclusions.size());
  }
  const std::vector<Box3>& known = stl.known;
  const std::vector<pipeline::SurfacePair>& unions = stl.unions;

  // Partition on rank 0, broadcast the boxes.
  std::vector<Box> boxes;
  Bytes message;
  {
    ScopedPhase timer(&out.times, "partition");
    run_collectively(comm, [&] {
      if (rank != 0) return;
      const partition::Partition p = partition::partition_domain(scene, n, options.partitioning, stl.loads);
      Packer pack;
      pack.put_string(p.method);
      std::vector<Box> parts;
      for (const auto& part : p.parts)
        parts.push_back(Box{part.id,
                            {part.lattice_min[0], part.lattice_min[1], part.lattice_min[2]},
                            {part.lattice_max[0], part.lattice_max[1], part.lattice_max[2]},
                            part.load});
      pack.put_vector(parts);
      message = pack.take();
    });
    std::vector<partition::InclusionLoad>().swap(stl.loads);
    message = broadcast_bytes(comm, message);
    run_collectively(comm, [&] {
      Unpacker u(message);
      out.partition_method = u.get_string();
      boxes = u.get_vector<Box>();
      std::sort(boxes.begin(), boxes.end(), [](const Box& a, const Box& b) { return a.id < b.id; });
      if (static_cast<int>(boxes.size()) != n) throw std::logic_error("partition: wrong number of parts");
    });
  }

  // Ghost regions of this rank's partitions, and the inclusions they need.
  const auto [first, last] = partitions_of_rank(n, ranks, rank);
  grid::Lattice<Dim> lattice;
  std::vector<int> levels;  // rule R1's level per scene inclusion
  std::vector<GhostRegion<Dim>> regions;
  {
    ScopedPhase timer(&out.times, "ghost");
    run_collectively(comm, [&] {
      lattice = scene_lattice<Dim>(scene, options.pipeline);
      const std::vector<Box3> holding = pipeline::holding_boxes(scene, known);
      // Every rank computes the same levels from the whole scene's descriptors (cheap:
      // pairs of nearby inclusions); they make SAMR local, so the ghost stays small.
      if constexpr (Dim == 2)
        levels = pipeline::effective_levels2(scene, lattice);
      else
        levels = pipeline::effective_levels3(scene, lattice, holding, unions);
      const InclusionIndex<Dim> index(scene, lattice, options.ghost, holding);
      for (int p = first; p < last; ++p) {
        grid::CellRange<Dim> box;
        for (int d = 0; d < Dim; ++d) {
          box.lo[d] = boxes[static_cast<std::size_t>(p)].lo[d];
          box.hi[d] = boxes[static_cast<std::size_t>(p)].hi[d];
        }
        if constexpr (Dim == 2)
          regions.push_back(ghost_region<2>(index, lattice, box, options.ghost));
        else
          regions.push_back(ghost_region3(index, lattice, box, options.ghost, levels));
        out.loaded_inclusions.insert(out.loaded_inclusions.end(), regions.back().inclusions.begin(),
                                     regions.back().inclusions.end());
      }
      std::sort(out.loaded_inclusions.begin(), out.loaded_inclusions.end());
      out.loaded_inclusions.erase(std::unique(out.loaded_inclusions.begin(), out.loaded_inclusions.end()),
                                  out.loaded_inclusions.end());
    });
  }

  // The descriptors this rank needs; the rest of the scene is dropped now. The STL
  // surfaces among them are read here (or taken from the files read above).
  geometry::SceneDesc needed;
  {
    ScopedPhase timer(&out.times, "read");
    run_collectively(comm, [&] {
      needed = subset_scene(scene, out.loaded_inclusions);
      std::vector<geometry::Inclusion>().swap(scene.inclusions);
      stl.files_read += io::load_stl_surfaces(needed, stl_inclusions(needed), &stl.cache);
      io::StlCache().swap(stl.cache);
    });
    out.stl_files_read = stl.files_read;
  }

  // The unchanged sequential kernel on each partition, with an oracle built from exactly
  // that partition's inclusions: its output (order included) is then the same whatever
  // the other partitions of its rank, so the gathered file does not depend on the ranks.
  std::vector<PartitionOutput<Dim>> outputs;
  std::vector<PartitionSummary> mine;
  KernelStats<Dim> local;
  run_collectively(comm, [&] {
    for (int p = first; p < last; ++p) {
      const GhostRegion<Dim>& region = regions[static_cast<std::size_t>(p - first)];
      std::unique_ptr<Oracle> oracle;
      {
        ScopedPhase timer(&out.times, "oracle");
        std::vector<std::int32_t> local_index;  // positions in `needed`
        for (std::int32_t k : region.inclusions)
          local_index.push_back(static_cast<std::int32_t>(
              std::lower_bound(out.loaded_inclusions.begin(), out.loaded_inclusions.end(), k) -
              out.loaded_inclusions.begin()));
        try {
          oracle = std::make_unique<Oracle>(subset_scene(needed, local_index));
        } catch (const InputError& e) {
          throw InputError(e.file(), rename_inclusions(e.field(), region.inclusions),
                           rename_inclusions(e.problem(), region.inclusions));
        }
      }
      const auto t0 = std::chrono::steady_clock::now();
      std::vector<int> region_levels;
      for (std::int32_t k : region.inclusions) region_levels.push_back(levels[static_cast<std::size_t>(k)]);
      PartitionOutput<Dim> o{p, region.box, run_kernel(*oracle, lattice, region, options.pipeline, p, region_levels)};
      std::int64_t box_cells = 1;
      for (int d = 0; d < Dim; ++d) box_cells *= region.box.count(d);
      PartitionSummary s;
      s.id = p;
      s.rank = rank;
      s.kernel_seconds = seconds_since(t0);
      for (int d = 0; d < Dim; ++d) s.lattice_min[d] = region.box.lo[d], s.lattice_max[d] = region.box.hi[d];
      s.load = boxes[static_cast<std::size_t>(p)].load;
      s.ghost = region.ghost;
      s.ghost_cells = coarse_cells_of(o.result.stats) - box_cells;
      s.inclusions = static_cast<std::int64_t>(region.inclusions.size());
      s.elements = static_cast<std::int64_t>(o.result.mesh.cell_count());
      s.nodes = static_cast<std::int64_t>(o.result.mesh.node_count());
      for (const auto& [name, sec] : o.result.stats.times.phases()) out.times.add(name, sec);
      accumulate(local, o.result.stats, box_cells);
      mine.push_back(s);
      outputs.push_back(std::move(o));
    }
  });

  {
    ScopedPhase timer(&out.times, "merge");
    out.piece = merge_and_number<Dim>(comm, outputs, lattice);
  }
  out.global_cells = comm.allreduce_sum(static_cast<std::int64_t>(out.piece.mesh.cell_count()));

  // Counters over all ranks. (leaves/refinements/... count ghost work too: they say what
  // was computed, not what was kept.)
  out.stats = reduce(comm, local);
  out.stats.max_level = lattice.max_level;

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

template DistributedMesh<2> mesh_distributed<2>(const Comm&, const std::string&, const MeshOptions&);
template DistributedMesh<3> mesh_distributed<3>(const Comm&, const std::string&, const MeshOptions&);
template DistributedMesh<2> mesh_distributed<2>(const Comm&, geometry::SceneDesc, const MeshOptions&);
template DistributedMesh<3> mesh_distributed<3>(const Comm&, geometry::SceneDesc, const MeshOptions&);

}  // namespace cisamr::parallel
