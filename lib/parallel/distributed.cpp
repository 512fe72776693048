#include "parallel/distributed.hpp"

#include <algorithm>
#include <chrono>
#include <limits>
#include <map>
#include <optional>
#include <type_traits>

#include "geometry/oracle.hpp"
#include "geometry/shapes.hpp"
#include "io/scene_io.hpp"
#include "parallel/cohesive.hpp"
#include "parallel/collective.hpp"
#include "parallel/exchange.hpp"
#include "parallel/near_faces.hpp"
#include "geometry/periodic.hpp"
#include "pipeline/effective_levels.hpp"

namespace cisamr::parallel {
namespace {

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// The kernel phase of a rank, measured in its partitions done; the stages of the partition
// being meshed (pipeline::run's phases, told as they begin and advance) add their share of
// it, so that the job's progress moves, and rank 0 keeps receiving the other ranks'
// messages, during a long partition too.
class PartitionProgress final : public Progress {
 public:
  PartitionProgress(Progress& kernel, int partitions, int phases_per_partition)
      : kernel_(kernel), partitions_(partitions), phases_per_partition_(phases_per_partition) {}
  // This rank's partition number `done` (from 0) begins.
  void start_partition(int done) {
    done_ = done;
    phases_ = 0;
    report(0);
  }
  void finish() { report_units(std::int64_t{partitions_} * kUnits); }
  void phase(const std::string&) override { ++phases_; }
  void advance(std::int64_t done, std::int64_t total) override {
    if (total > 0 && phases_ > 0)
      report((phases_ - 1 + static_cast<double>(done) / static_cast<double>(total)) / phases_per_partition_);
  }

 private:
  static constexpr std::int64_t kUnits = 1 << 16;  // per partition
  Progress& kernel_;
  const int partitions_, phases_per_partition_;
  int done_ = 0, phases_ = 0;
  std::int64_t reported_ = 0;

  void report(double partition_fraction) {
    report_units(done_ * kUnits + static_cast<std::int64_t>(std::clamp(partition_fraction, 0.0, 1.0) * kUnits));
  }
  void report_units(std::int64_t units) {
    reported_ = std::max(reported_, units);  // never backwards, whatever a stage reports
    kernel_.advance(reported_, std::int64_t{partitions_} * kUnits);
  }
};

}  // namespace

// Not in the anonymous namespace: the exported templates' lambdas capture them.
namespace distributed_detail {
struct Box {  // a partition as broadcast by rank 0
  std::int32_t id;
  std::int64_t lo[3], hi[3];
  double load, cost;
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

  std::vector<StlBox> boxes;
  Packer loads;
  run_collectively(comm, [&] {
    out.files_read += io::load_stl_surfaces(scene, mine, &out.cache);
    for (std::int32_t k : mine) {
      const geometry::Inclusion& inc = scene.inclusions[static_cast<std::size_t>(k)];
      boxes.push_back({k, geometry::shape_bounding_box(inc.shape)});
      if (!loads_needed) continue;
      const partition::InclusionLoad load = partition::stl_surface_load(scene, k, popt);
      loads.put<std::int32_t>(k);
      loads.put_vector(load.cells);
      loads.put_vector(load.loads);
      loads.put(load.box);
    }
  });
  for (const StlBox& b : allgather_vector(comm, boxes)) out.known[static_cast<std::size_t>(b.inclusion)] = b.box;
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
  std::vector<pipeline::SurfacePair> found;
  run_collectively(comm, [&] {
    const std::vector<Box3> box = pipeline::holding_boxes(scene, out.known);
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
  });
  out.unions = allgather_vector(comm, found);
  std::sort(out.unions.begin(), out.unions.end());
  // Triangles stay in the cache only (for the partitions that need them later).
  for (std::int32_t k : unread)
    std::get<geometry::StlSurface>(scene.inclusions[static_cast<std::size_t>(k)].shape).triangles.clear();
  return out;
}

namespace {

// Counters over every rank's partitions, each combined as its Reduction says.
template <int Dim>
pipeline::Counters<Dim> reduce_over_ranks(const Comm& comm, const pipeline::Counters<Dim>& local) {
  pipeline::Counters<Dim> global = local;
  pipeline::Counters<Dim>::for_each([&](const char*, auto member, pipeline::Reduction reduction) {
    auto& value = global.*member;
    using T = std::remove_reference_t<decltype(value)>;
    // Integers travel as int64 (exact), the rest as double.
    using Wide = std::conditional_t<std::is_integral_v<T>, std::int64_t, double>;
    const Wide v = value;
    switch (reduction) {
      case pipeline::Reduction::sum: value = static_cast<T>(comm.allreduce_sum(v)); break;
      case pipeline::Reduction::max: value = static_cast<T>(comm.allreduce_max(v)); break;
      case pipeline::Reduction::min: {  // of the set values (≥ 0); −1 when no rank has one
        const Wide least = comm.allreduce_max(v >= 0 ? -v : std::numeric_limits<Wide>::lowest());
        value = static_cast<T>(least == std::numeric_limits<Wide>::lowest() ? -1 : -least);
        break;
      }
    }
  });
  return global;
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
DistributedMesh<Dim> mesh_partitions(const Comm& comm, geometry::SceneDesc scene, const MeshOptions& options,
                                     const PartitionSink<Dim>& sink) {
  using Oracle = geometry::Oracle<Dim>;
  DistributedMesh<Dim> out;
  const int ranks = comm.size(), rank = comm.rank();
  const int n = options.partitions;
  Progress* const progress = options.pipeline.progress;  // this rank's (the driver: rank 0's)
  out.times.progress = progress;
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
      const partition::Partition p =
          partition::partition_domain(scene, n, ghost_aware(options.partitioning, Dim, options.ghost), stl.loads);
      Packer pack;
      pack.put_string(p.method);
      std::vector<Box> parts;
      for (const auto& part : p.parts)
        parts.push_back(Box{part.id,
                            {part.lattice_min[0], part.lattice_min[1], part.lattice_min[2]},
                            {part.lattice_max[0], part.lattice_max[1], part.lattice_max[2]},
                            part.load, part.cost});
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

  // A periodic scene: the partitions tile the domain as it is (their loads wrap); the kernel
  // meshes the torus and needs the images of inclusions near the faces (geometry/periodic.hpp).
  std::vector<Box3> expanded_known;
  if (scene.any_periodic())
    run_collectively(comm, [&] {
      (void)scene_lattice<Dim>(scene, options.pipeline);  // refuses what it cannot mesh (3D) before expanding
      scene = geometry::expand_periodic(scene, geometry::periodic_reach(scene), known);
      out.periodic_images = geometry::images_in_domain(scene, known);
      expanded_known = geometry::expanded_boxes(scene, known);
    });
  const std::vector<Box3>& known_boxes = scene.image_base.empty() ? known : expanded_known;

  // Ghost regions of this rank's partitions, and the inclusions they need.
  const auto [first, last] = partitions_of_rank(n, ranks, rank);
  GhostRule rule = options.ghost;
  rule.exchange = Dim == 3 && options.exchange_near_faces;
  grid::Lattice<Dim> lattice;
  std::vector<int> levels;  // rule R1's level per scene inclusion
  std::vector<GhostRegion<Dim>> regions;
  {
    ScopedPhase timer(&out.times, "ghost");
    run_collectively(comm, [&] {
      lattice = scene_lattice<Dim>(scene, options.pipeline);
      const std::vector<Box3> holding = pipeline::holding_boxes(scene, known_boxes);
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
          regions.push_back(ghost_region3(index, lattice, box, rule, levels));
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
  // With the decisions near faces exchanged (3D, GhostRule::exchange) it runs in parts, every
  // partition of the rank through one before the next: SAMR and the guard's first pass, the
  // refusals exchanged, the second pass, the decisions exchanged, then the rest.
  const bool exchange = Dim == 3 && exchanges_near_faces(rule, lattice.any_periodic());
  const int count = last - first;
  std::vector<PartitionSummary> mine;
  pipeline::Counters<Dim> local;
  // Progress: the kernel as one phase, advanced per partition and within it by its stages
  // (the first and last parts when it runs in parts).
  std::optional<PartitionProgress> partition_progress;
  if (progress != nullptr)
    partition_progress.emplace(*progress, exchange ? 2 * count : count, exchange ? 3 : pipeline::kRunPhases<Dim>);
  pipeline::Options kernel_options = options.pipeline;
  kernel_options.progress = partition_progress ? &*partition_progress : nullptr;
  out.times.progress = nullptr;
  begin_phase(progress, "kernel");
  std::vector<std::unique_ptr<Oracle>> oracles(static_cast<std::size_t>(count));
  std::vector<std::vector<int>> region_levels(static_cast<std::size_t>(count));
  // Kernel time per partition by its parts between exchanges (one part when nothing is
  // exchanged): on a rank per partition each part waits for the slowest partition's.
  std::vector<std::array<double, kKernelStages>> stage_seconds(static_cast<std::size_t>(count));
  const auto prepare = [&](int p) {
    const GhostRegion<Dim>& region = regions[static_cast<std::size_t>(p - first)];
    ScopedPhase timer(&out.times, "oracle");
    std::vector<std::int32_t> local_index;  // positions in `needed`
    for (std::int32_t k : region.inclusions)
      local_index.push_back(static_cast<std::int32_t>(
          std::lower_bound(out.loaded_inclusions.begin(), out.loaded_inclusions.end(), k) -
          out.loaded_inclusions.begin()));
    // (A subset scene names its inclusions as the scene file does.)
    oracles[static_cast<std::size_t>(p - first)] = std::make_unique<Oracle>(subset_scene(needed, local_index));
    for (std::int32_t k : region.inclusions)
      region_levels[static_cast<std::size_t>(p - first)].push_back(levels[static_cast<std::size_t>(k)]);
  };
  const auto deliver = [&](int p, pipeline::Result<Dim>&& result) {
    const GhostRegion<Dim>& region = regions[static_cast<std::size_t>(p - first)];
    PartitionOutput<Dim> o{p, region.box, std::move(result)};
    std::int64_t box_cells = 1;
    for (int d = 0; d < Dim; ++d) box_cells *= region.box.count(d);
    PartitionSummary s;
    s.id = p;
    s.rank = rank;
    s.stage_seconds = stage_seconds[static_cast<std::size_t>(p - first)];
    for (double sec : s.stage_seconds) s.kernel_seconds += sec;
    for (int d = 0; d < Dim; ++d) s.lattice_min[d] = region.box.lo[d], s.lattice_max[d] = region.box.hi[d];
    s.load = boxes[static_cast<std::size_t>(p)].load;
    s.cost = boxes[static_cast<std::size_t>(p)].cost;
    s.ghost = region.ghost;
    s.ghost_cells = o.result.counters.coarse_cells - box_cells;
    s.inclusions = static_cast<std::int64_t>(region.inclusions.size());
    s.elements = static_cast<std::int64_t>(o.result.mesh.cell_count());
    s.nodes = static_cast<std::int64_t>(o.result.mesh.node_count());
    for (const auto& [name, sec] : o.result.times.phases()) out.times.add(name, sec);
    // The box's coarse cells only (the partitions tile the domain); ghost work is in
    // the other counters and in the summary.
    o.result.counters.coarse_cells = box_cells;
    pipeline::accumulate(local, o.result.counters);
    mine.push_back(s);
    oracles[static_cast<std::size_t>(p - first)].reset();
    sink(o, lattice);
  };
  if constexpr (Dim == 3) {
    if (exchange) {
      std::vector<pipeline::Snapped3> snapped;
      snapped.reserve(static_cast<std::size_t>(count));
      run_collectively(comm, [&] {
        for (int p = first; p < last; ++p) {
          if (partition_progress) partition_progress->start_partition(p - first);
          prepare(p);
          const auto t0 = std::chrono::steady_clock::now();
          const GhostRegion3& region = regions[static_cast<std::size_t>(p - first)];
          snapped.push_back(pipeline::refine3_part(*oracles[static_cast<std::size_t>(p - first)], lattice, region.box,
                                                   kernel_ghost(region), kernel_options,
                                                   region_levels[static_cast<std::size_t>(p - first)]));
          stage_seconds[static_cast<std::size_t>(p - first)][0] = seconds_since(t0);
        }
      });
      std::vector<grid::CellRange<3>> all_boxes(boxes.size());
      for (std::size_t q = 0; q < boxes.size(); ++q)
        for (int d = 0; d < 3; ++d) all_boxes[q].lo[d] = boxes[q].lo[d], all_boxes[q].hi[d] = boxes[q].hi[d];
      std::vector<SnappedPartition> waiting;
      for (int p = first; p < last; ++p) {
        const GhostRegion3& region = regions[static_cast<std::size_t>(p - first)];
        waiting.push_back({p, region.exchange, region.second_pass_reach, &snapped[static_cast<std::size_t>(p - first)]});
      }
      std::vector<std::vector<samr::CubeRefinement>> owners_cubes;
      {
        ScopedPhase timer(&out.times, "exchange");
        std::int64_t cubes = 0;
        owners_cubes = exchange_forests(comm, all_boxes, waiting, cubes);
        out.exchanged_cubes = comm.allreduce_sum(cubes);
      }
      std::int64_t replaced = 0;
      run_collectively(comm, [&] {
        for (int p = first; p < last; ++p) {
          const auto i = static_cast<std::size_t>(p - first);
          const auto t0 = std::chrono::steady_clock::now();
          const GhostRegion3& region = regions[i];
          {
            ScopedPhase timer(&snapped[i].result.times, "samr");
            replaced += samr::take_cube_refinements(*oracles[i], *snapped[i].grid, owners_cubes[i]);
          }
          std::vector<samr::CubeRefinement>().swap(owners_cubes[i]);
          pipeline::snap3_first(*oracles[i], lattice, region.box, kernel_ghost(region), kernel_options, snapped[i]);
          stage_seconds[i][1] = seconds_since(t0);
        }
      });
      out.replaced_cubes = comm.allreduce_sum(replaced);
      {
        ScopedPhase timer(&out.times, "exchange");
        out.exchanged_nodes = comm.allreduce_sum(exchange_first_pass_refusals(comm, lattice, all_boxes, waiting));
      }
      run_collectively(comm, [&] {
        for (int p = first; p < last; ++p) {
          const auto t0 = std::chrono::steady_clock::now();
          pipeline::snap3_second(snapped[static_cast<std::size_t>(p - first)], kernel_options);
          stage_seconds[static_cast<std::size_t>(p - first)][2] = seconds_since(t0);
        }
      });
      {
        ScopedPhase timer(&out.times, "exchange");
        out.exchanged_nodes += comm.allreduce_sum(exchange_decisions(comm, lattice, all_boxes, waiting));
        out.near_faces_exchanged = true;
      }
      run_collectively(comm, [&] {
        for (int p = first; p < last; ++p) {
          if (partition_progress) partition_progress->start_partition(count + p - first);
          const auto t0 = std::chrono::steady_clock::now();
          const GhostRegion3& region = regions[static_cast<std::size_t>(p - first)];
          pipeline::Result<3> result =
              pipeline::finish3(*oracles[static_cast<std::size_t>(p - first)], lattice, region.box, kernel_ghost(region),
                                kernel_options, p, std::move(snapped[static_cast<std::size_t>(p - first)]));
          stage_seconds[static_cast<std::size_t>(p - first)][3] = seconds_since(t0);
          deliver(p, std::move(result));
        }
        if (partition_progress) partition_progress->finish();
      });
    }
  }
  if (!exchange)
    run_collectively(comm, [&] {
      for (int p = first; p < last; ++p) {
        if (partition_progress) partition_progress->start_partition(p - first);
        prepare(p);
        const auto t0 = std::chrono::steady_clock::now();
        const GhostRegion<Dim>& region = regions[static_cast<std::size_t>(p - first)];
        pipeline::Result<Dim> result = pipeline::run(*oracles[static_cast<std::size_t>(p - first)], lattice, region.box,
                                                     kernel_ghost(region), kernel_options, p,
                                                     region_levels[static_cast<std::size_t>(p - first)]);
        stage_seconds[static_cast<std::size_t>(p - first)][0] = seconds_since(t0);
        deliver(p, std::move(result));
      }
      if (partition_progress) partition_progress->finish();
    });
  out.times.progress = progress;

  // Counters over all ranks. (leaves/refinements/... count ghost work too: they say what
  // was computed, not what was kept.)
  out.counters = reduce_over_ranks(comm, local);

  // Every partition's summary on every rank.
  out.partitions = allgather_vector(comm, mine);
  std::sort(out.partitions.begin(), out.partitions.end(),
            [](const PartitionSummary& a, const PartitionSummary& b) { return a.id < b.id; });
  for (const PartitionSummary& s : out.partitions) out.global_cells += s.elements;
  return out;
}

template <int Dim>
DistributedMesh<Dim> mesh_distributed(const Comm& comm, geometry::SceneDesc scene, const MeshOptions& options) {
  std::vector<PartitionOutput<Dim>> outputs;
  grid::Lattice<Dim> lattice;
  DistributedMesh<Dim> out =
      mesh_partitions<Dim>(comm, std::move(scene), options, [&](PartitionOutput<Dim>& o, const grid::Lattice<Dim>& l) {
        outputs.push_back(std::move(o));
        lattice = l;
      });
  if (options.pipeline.cohesive) {
    ScopedPhase timer(&out.times, "cohesive");
    join_cohesive<Dim>(comm, outputs, lattice);
  }
  {
    ScopedPhase timer(&out.times, "merge");
    out.piece = merge_and_number<Dim>(comm, outputs, lattice, options.pipeline.cohesive);
  }
  return out;
}

template DistributedMesh<2> mesh_distributed<2>(const Comm&, const std::string&, const MeshOptions&);
template DistributedMesh<3> mesh_distributed<3>(const Comm&, const std::string&, const MeshOptions&);
template DistributedMesh<2> mesh_distributed<2>(const Comm&, geometry::SceneDesc, const MeshOptions&);
template DistributedMesh<2> mesh_partitions<2>(const Comm&, geometry::SceneDesc, const MeshOptions&, const PartitionSink<2>&);
template DistributedMesh<3> mesh_partitions<3>(const Comm&, geometry::SceneDesc, const MeshOptions&, const PartitionSink<3>&);
template DistributedMesh<3> mesh_distributed<3>(const Comm&, geometry::SceneDesc, const MeshOptions&);

}  // namespace cisamr::parallel
