// The certificate of a mesh given piece by piece (pieces.hpp): per piece, what only it
// holds; across pieces, the border: the nodes several pieces hold (marked in a bitmap over
// global ids in a first pass), the facets made of those, and the pieces' open facets.
#include "quality/pieces.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <optional>
#include <stdexcept>

#include "core/error.hpp"
#include "quality/pieces_internal.hpp"
#include "quality/scene_queries.hpp"

namespace cisamr::quality {
namespace {

constexpr std::size_t kMaxExamples = 24;
// Node ids are LocalId once merged (io::read_mesh): larger ids are not marked (256 MiB of bits).
constexpr GlobalId kLargestMarkableId = GlobalId(1) << 31;

// A set of non-negative ids as bits, grown as ids come, with ranks once frozen.
class IdBits {
 public:
  // Sets id's bit; returns whether it was set before.
  bool insert(GlobalId id) {
    const auto word = static_cast<std::size_t>(id) >> 6;
    if (word >= words_.size()) words_.resize(std::max(word + 1, 2 * words_.size()), 0);
    const std::uint64_t bit = std::uint64_t(1) << (id & 63);
    const bool was = (words_[word] & bit) != 0;
    words_[word] |= bit;
    return was;
  }
  bool contains(GlobalId id) const {
    const auto word = static_cast<std::size_t>(id) >> 6;
    return id >= 0 && word < words_.size() && ((words_[word] >> (id & 63)) & 1) != 0;
  }
  // Freezes the set: rank(id) = the number of ids below it.
  void index() {
    rank_before_.assign(words_.size() + 1, 0);
    for (std::size_t w = 0; w < words_.size(); ++w)
      rank_before_[w + 1] = rank_before_[w] + static_cast<std::size_t>(std::popcount(words_[w]));
  }
  std::size_t size() const { return rank_before_.empty() ? 0 : rank_before_.back(); }
  std::size_t rank(GlobalId id) const {
    const auto word = static_cast<std::size_t>(id) >> 6;
    const std::uint64_t below = (std::uint64_t(1) << (id & 63)) - 1;
    return rank_before_[word] + static_cast<std::size_t>(std::popcount(words_[word] & below));
  }
  std::size_t count() const {
    std::size_t n = 0;
    for (const std::uint64_t w : words_) n += static_cast<std::size_t>(std::popcount(w));
    return n;
  }
  // Calls visit(id) for every id, ascending.
  template <class Visit>
  void for_each(Visit&& visit) const {
    for (std::size_t w = 0; w < words_.size(); ++w)
      for (std::uint64_t bits = words_[w]; bits != 0; bits &= bits - 1)
        visit(static_cast<GlobalId>(64 * w + static_cast<std::size_t>(std::countr_zero(bits))));
  }

 private:
  std::vector<std::uint64_t> words_;
  std::vector<std::size_t> rank_before_;
};

template <int Dim>
std::string point_text(const double* p) {
  Vec<Dim> v;
  std::copy(p, p + Dim, v.begin());
  return detail::point_text<Dim>(v);
}

// Moves the examples from index `from` on behind "name: ", keeping at most kMaxExamples.
void prefix_examples(std::vector<std::string>& examples, std::size_t from, const std::string& name) {
  for (std::size_t i = from; i < examples.size(); ++i) examples[i] = name + ": " + examples[i];
  if (examples.size() > kMaxExamples) examples.resize(kMaxExamples);
}

void add_counts(ConformityReport& total, const ConformityReport& piece, const std::string& name) {
  total.duplicate_nodes += piece.duplicate_nodes;
  total.degenerate_cells += piece.degenerate_cells;
  total.inverted_cells += piece.inverted_cells;
  total.bad_node_references += piece.bad_node_references;
  total.non_manifold_facets += piece.non_manifold_facets;
  total.mismatched_orientation_facets += piece.mismatched_orientation_facets;
  total.open_facets_inside += piece.open_facets_inside;
  total.inner_boundary_facets += piece.inner_boundary_facets;
  total.boundary_facets += piece.boundary_facets;
  total.hanging_nodes += piece.hanging_nodes;
  total.unused_nodes += piece.unused_nodes;
  total.measure += piece.measure;
  const std::size_t from = total.examples.size();
  for (const std::string& e : piece.examples)
    if (total.examples.size() < kMaxExamples) total.examples.push_back(e);
  prefix_examples(total.examples, from, name);
}

void add_fidelity_counts(FidelityReport& total, const FidelityReport& piece, const std::string& name) {
  total.nodes_off_phase += piece.nodes_off_phase;
  total.interface_nodes_off_interface += piece.interface_nodes_off_interface;
  total.boundary_nodes_off_void += piece.boundary_nodes_off_void;
  total.cells_unknown_phase += piece.cells_unknown_phase;
  total.nodes_beyond_strict += piece.nodes_beyond_strict;
  total.cells_off_phase += piece.cells_off_phase;
  total.cells_wrong_phase += piece.cells_wrong_phase;
  total.max_deviation = std::max(total.max_deviation, piece.max_deviation);
  total.max_centroid_ratio = std::max(total.max_centroid_ratio, piece.max_centroid_ratio);
  for (std::size_t k = 0; k < total.phase_measure.size() && k < piece.phase_measure.size(); ++k)
    total.phase_measure[k] += piece.phase_measure[k];
  const std::size_t from = total.examples.size();
  for (const std::string& e : piece.examples)
    if (total.examples.size() < kMaxExamples) total.examples.push_back(e);
  prefix_examples(total.examples, from, name);
}

// The worst cells of two lists (cell ids over all pieces), worst first, ties by smaller id.
void merge_worst(std::vector<AspectStats::Worst>& total, const std::vector<AspectStats::Worst>& part,
                 std::size_t cell_offset, int keep) {
  for (AspectStats::Worst w : part) {
    w.cell += cell_offset;
    total.push_back(w);
  }
  std::stable_sort(total.begin(), total.end(), [](const AspectStats::Worst& a, const AspectStats::Worst& b) {
    return a.aspect_ratio != b.aspect_ratio ? a.aspect_ratio > b.aspect_ratio : a.cell < b.cell;
  });
  if (total.size() > static_cast<std::size_t>(std::max(keep, 0))) total.resize(static_cast<std::size_t>(std::max(keep, 0)));
}

}  // namespace

template <int Dim>
struct PiecewiseCertifier<Dim>::State {
  CertifyOptions options;
  const geometry::Oracle<Dim>* oracle = nullptr;
  std::optional<detail::SceneTerms<Dim>> scene;
  double bound = 0;

  // First pass.
  IdBits seen, shared;
  GlobalId largest_id = -1;
  bool negative_id = false;
  std::size_t nodes_listed = 0;
  Box<Dim> bounds;
  bool any_node = false;

  // Second pass.
  bool started = false;
  Box<Dim> domain;
  std::size_t pieces = 0, cells = 0, largest_piece = 0;
  std::map<int, std::size_t> cells_per_phase;
  AspectStats aspect;
  std::vector<AspectStats::Worst> worst;
  ConformityReport conformity;
  std::optional<FidelityReport> fidelity;
  // Per shared node, by rank: coordinates (NaN until a piece gives them), used, verdict.
  std::vector<double> shared_coords;
  std::vector<bool> shared_used;
  std::vector<detail::NodeVerdict> shared_verdict;
  std::vector<GlobalId> shared_ids;  // by rank
  GlobalId shared_ids_by_rank(std::size_t rank) const { return shared_ids[rank]; }
  std::vector<detail::BorderFacetUse<Dim>> shared_facets;  // nodes: shared ranks
  std::vector<std::array<GlobalId, Dim>> open_facets;
  std::vector<std::pair<GlobalId, std::array<double, Dim>>> open_nodes;  // unshared nodes of open facets

  void start() {
    started = true;
    shared.index();
    if (scene) {
      domain = scene->domain;
    } else {
      domain = bounds;
    }
    aspect.bound = bound;
    shared_coords.assign(Dim * shared.size(), std::numeric_limits<double>::quiet_NaN());
    shared_used.assign(shared.size(), false);
    shared_verdict.assign(shared.size(), detail::NodeVerdict{});
    shared.for_each([&](GlobalId id) { shared_ids.push_back(id); });
    if (scene) fidelity = detail::start_fidelity<Dim>(*oracle, scene->fidelity_tolerance, scene->exact_measures);
  }
};

template <int Dim>
PiecewiseCertifier<Dim>::PiecewiseCertifier(const CertifyOptions& options, const geometry::Oracle<Dim>* oracle)
    : s_(std::make_unique<State>()) {
  s_->options = options;
  s_->oracle = oracle;
  if (oracle) {
    s_->scene = detail::scene_terms<Dim>(*oracle, options);
    s_->options = s_->scene->options;
  } else {
    // Without a scene a void cannot be told from a hole (as certify without a scene in cisamr certify).
    s_->options.allow_inner_boundary = true;
  }
  s_->bound = options.bound > 0 ? options.bound : default_bound(Dim);
}

template <int Dim>
PiecewiseCertifier<Dim>::~PiecewiseCertifier() = default;

template <int Dim>
void PiecewiseCertifier<Dim>::count_nodes(std::span<const GlobalId> ids, std::span<const double> coords3) {
  State& s = *s_;
  s.nodes_listed += ids.size();
  for (std::size_t n = 0; n < ids.size(); ++n) {
    const GlobalId id = ids[n];
    if (id < 0) {
      s.negative_id = true;
      continue;
    }
    s.largest_id = std::max(s.largest_id, id);
    if (id >= kLargestMarkableId) continue;  // ids_usable() says no
    if (s.seen.insert(id)) s.shared.insert(id);
    const double* p = &coords3[3 * n];
    for (int d = 0; d < Dim; ++d) {
      s.bounds.min[d] = s.any_node ? std::min(s.bounds.min[d], p[d]) : p[d];
      s.bounds.max[d] = s.any_node ? std::max(s.bounds.max[d], p[d]) : p[d];
    }
    s.any_node = true;
  }
}

template <int Dim>
bool PiecewiseCertifier<Dim>::ids_usable() const {
  return !s_->negative_id && s_->largest_id < kLargestMarkableId &&
         s_->largest_id < GlobalId(4 * s_->nodes_listed + (std::size_t(1) << 20));
}

template <int Dim>
struct PiecewiseCertifier<Dim>::Checked {
  std::string name;
  std::size_t cells = 0;
  std::map<int, std::size_t> cells_per_phase;
  AspectStats aspect;
  ConformityReport conformity;
  std::vector<detail::BorderFacetUse<Dim>> shared_facets;  // nodes: shared ranks; cells: the piece's
  std::vector<std::array<GlobalId, Dim>> open_facets;
  std::vector<std::pair<GlobalId, std::array<double, Dim>>> open_nodes;
  struct SharedNode {
    LocalId local = 0;
    std::size_t rank = 0;
    std::array<double, Dim> point{};
    bool used = false;
    detail::NodeVerdict verdict;
  };
  std::vector<SharedNode> shared_nodes;
  std::optional<FidelityReport> fidelity;  // this piece's counts
};

template <int Dim>
void PiecewiseCertifier<Dim>::end_first_pass() {
  if (!s_->started) s_->start();
}

template <int Dim>
void PiecewiseCertifier<Dim>::CheckedDeleter::operator()(Checked* c) const {
  delete c;
}

template <int Dim>
typename PiecewiseCertifier<Dim>::CheckedPiece PiecewiseCertifier<Dim>::check_piece(const mesh::SimplexMesh<Dim>& m,
                                                                                   const std::string& name) const {
  const State& s = *s_;
  if (!s.started) throw std::logic_error("PiecewiseCertifier: check_piece before end_first_pass");
  const std::size_t nodes = m.node_count();
  if (m.node_global_id.size() != nodes) throw std::logic_error("PiecewiseCertifier: a piece without global ids");
  CheckedPiece out(new Checked);
  out->name = name;
  out->cells = m.cell_count();
  std::vector<bool> is_shared(nodes);
  for (std::size_t n = 0; n < nodes; ++n) {
    const GlobalId id = m.node_global_id[n];
    if (!s.seen.contains(id))
      throw InputError(name, "global_id", "node " + std::to_string(n) + " has global id " + std::to_string(id) +
                                              ", which the first pass did not see (the piece changed?)");
    is_shared[n] = s.shared.contains(id);
    if (!is_shared[n]) continue;
    typename Checked::SharedNode node;
    node.local = LocalId(n);
    node.rank = s.shared.rank(id);
    std::copy(&m.coords[Dim * n], &m.coords[Dim * n] + Dim, node.point.begin());
    out->shared_nodes.push_back(node);
  }

  // Cells and aspect ratio.
  for (std::size_t c = 0; c < m.cell_count(); ++c) ++out->cells_per_phase[c < m.cell_phase.size() ? m.cell_phase[c] : 0];
  out->aspect = aspect_statistics<Dim>(m, s.bound, s.options.worst_count);

  // Conformity; the facets between pieces numbered by shared rank.
  detail::PieceBorder<Dim> border;
  detail::check_piece_conformity<Dim>(m, is_shared, s.domain, s.options.allow_inner_boundary, 0, out->conformity,
                                      border);
  for (typename Checked::SharedNode& node : out->shared_nodes) node.used = border.used[std::size_t(node.local)];
  out->shared_facets.reserve(border.shared_facets.size());
  for (const detail::GlobalFacet<Dim>& g : border.shared_facets) {
    detail::BorderFacetUse<Dim> u;
    for (int k = 0; k < Dim; ++k) u.nodes[k] = static_cast<LocalId>(s.shared.rank(g.ids[k]));
    u.use.cell = g.cell;
    u.use.odd = g.odd;
    out->shared_facets.push_back(u);
  }
  out->open_facets = std::move(border.open_facets);
  for (const LocalId n : border.open_nodes) {
    std::array<double, Dim> p;
    for (int d = 0; d < Dim; ++d) p[d] = m.coords[Dim * std::size_t(n) + d];
    out->open_nodes.emplace_back(m.node_global_id[std::size_t(n)], p);
  }

  // Fidelity: the shared nodes' verdicts wait for their phases in every piece.
  if (s.scene) {
    out->fidelity = detail::start_fidelity<Dim>(*s.oracle, s.scene->fidelity_tolerance, s.scene->exact_measures);
    std::vector<std::pair<LocalId, detail::NodeVerdict>> verdicts;
    detail::check_mesh_fidelity<Dim>(m, *s.oracle, s.scene->fidelity_tolerance, -1, &is_shared, &verdicts,
                                     *out->fidelity);
    std::size_t i = 0;  // verdicts and shared_nodes both ascend by local id
    for (const auto& [n, v] : verdicts) {
      while (out->shared_nodes[i].local != n) ++i;
      out->shared_nodes[i].verdict = v;
    }
  }
  return out;
}

template <int Dim>
void PiecewiseCertifier<Dim>::add_checked(CheckedPiece piece) {
  State& s = *s_;
  const Checked& p = *piece;
  for (const typename Checked::SharedNode& node : p.shared_nodes) {
    double* stored = &s.shared_coords[Dim * node.rank];
    if (std::isnan(stored[0])) {
      std::copy(node.point.begin(), node.point.end(), stored);
    } else if (!std::equal(node.point.begin(), node.point.end(), stored)) {
      throw InputError(p.name, "global_id",
                       "node " + std::to_string(node.local) + " (global id " +
                           std::to_string(s.shared_ids_by_rank(node.rank)) + ") is at " +
                           point_text<Dim>(node.point.data()) + " here but at " + point_text<Dim>(stored) +
                           " in an earlier piece");
    }
    s.shared_used[node.rank] = s.shared_used[node.rank] || node.used;
    detail::NodeVerdict& merged = s.shared_verdict[node.rank];
    const detail::NodeVerdict& v = node.verdict;
    merged.mask |= v.mask;
    merged.closure = v.closure;
    merged.beyond_strict = merged.beyond_strict || v.beyond_strict;
    if (!(v.worst <= merged.worst)) merged.worst = v.worst, merged.worst_phase = v.worst_phase;
  }
  for (const auto& [phase, count] : p.cells_per_phase) s.cells_per_phase[phase] += count;
  merge_worst(s.worst, p.aspect.worst, s.cells, s.options.worst_count);
  merge_into(s.aspect, p.aspect);
  add_counts(s.conformity, p.conformity, p.name);
  for (detail::BorderFacetUse<Dim> u : p.shared_facets) {
    u.use.cell += s.cells;
    s.shared_facets.push_back(u);
  }
  s.open_facets.insert(s.open_facets.end(), p.open_facets.begin(), p.open_facets.end());
  s.open_nodes.insert(s.open_nodes.end(), p.open_nodes.begin(), p.open_nodes.end());
  if (p.fidelity) add_fidelity_counts(*s.fidelity, *p.fidelity, p.name);
  s.cells += p.cells;
  s.largest_piece = std::max(s.largest_piece, p.cells);
  ++s.pieces;
}

template <int Dim>
void PiecewiseCertifier<Dim>::add_piece(const mesh::SimplexMesh<Dim>& m, const std::string& name) {
  end_first_pass();
  add_checked(check_piece(m, name));
}

template <int Dim>
Certificate PiecewiseCertifier<Dim>::finish() {
  State& s = *s_;
  if (!s.started) s.start();
  // The border mesh: the shared nodes by rank, then the unshared nodes of open facets by id.
  std::sort(s.open_nodes.begin(), s.open_nodes.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  s.open_nodes.erase(std::unique(s.open_nodes.begin(), s.open_nodes.end(),
                                 [](const auto& a, const auto& b) { return a.first == b.first; }),
                     s.open_nodes.end());
  mesh::SimplexMesh<Dim> border;
  border.coords = std::move(s.shared_coords);
  border.node_global_id = std::move(s.shared_ids);
  for (const auto& [id, p] : s.open_nodes) {
    border.coords.insert(border.coords.end(), p.begin(), p.end());
    border.node_global_id.push_back(id);
  }
  const auto border_id = [&](GlobalId id) {
    if (s.shared.contains(id)) return static_cast<LocalId>(s.shared.rank(id));
    const auto it = std::lower_bound(s.open_nodes.begin(), s.open_nodes.end(), id,
                                     [](const auto& a, GlobalId b) { return a.first < b; });
    return static_cast<LocalId>(s.shared.size() + static_cast<std::size_t>(it - s.open_nodes.begin()));
  };
  std::vector<detail::FacetNodes<Dim>> open;
  open.reserve(s.open_facets.size());
  for (const auto& ids : s.open_facets) {
    detail::FacetNodes<Dim> f;
    for (int k = 0; k < Dim; ++k) f[k] = border_id(ids[k]);
    std::sort(f.begin(), f.end());
    open.push_back(f);
  }
  s.open_facets = {};

  ConformityReport& r = s.conformity;
  const std::size_t from = r.examples.size();
  for (std::size_t k = 0; k < s.shared_used.size(); ++k)
    if (!s.shared_used[k]) {
      ++r.unused_nodes;
      if (r.examples.size() < kMaxExamples)
        r.examples.push_back("unused node with global id " + std::to_string(border.node_global_id[k]) + " " +
                             point_text<Dim>(&border.coords[Dim * k]));
    }
  const std::vector<LocalId> void_nodes =
      detail::check_border_conformity<Dim>(border, s.shared_facets, open, s.domain, s.options.allow_inner_boundary, r);
  prefix_examples(r.examples, from, "across pieces (node ids global)");
  detail::finish_piecewise_conformity(r, s.options.expected_measure, s.options.measure_tolerance);

  Certificate c;
  c.dimension = Dim;
  c.node_count = s.seen.count();
  c.cell_count = s.cells;
  c.cells_per_phase.assign(s.cells_per_phase.begin(), s.cells_per_phase.end());
  for (int d = 0; d < Dim; ++d) c.domain.min[d] = s.domain.min[d], c.domain.max[d] = s.domain.max[d];
  c.aspect = s.aspect;
  c.aspect.bound = s.bound;
  c.aspect.worst = s.worst;
  c.conformity = r;
  if (s.options.expected_measure < 0) c.notes.push_back("total measure not checked (no expected measure)");
  if (s.fidelity) {
    FidelityReport& f = *s.fidelity;
    const geometry::SceneDesc& scene = s.oracle->scene();
    const std::size_t fidelity_from = f.examples.size();
    for (std::size_t k = 0; k < s.shared_verdict.size(); ++k)
      if (s.shared_verdict[k].mask != 0)
        detail::count_node<Dim>(f, scene, s.shared_verdict[k], f.tolerance,
                                "with global id " + std::to_string(border.node_global_id[k]) + " " +
                                    point_text<Dim>(&border.coords[Dim * k]));
    detail::check_void_boundary_nodes<Dim>(border, void_nodes, *s.oracle, f.tolerance, f);
    prefix_examples(f.examples, fidelity_from, "across pieces (node ids global)");
    detail::finish_fidelity<Dim>(scene, f);
    c.fidelity = f;
    c.scene_source = scene.source;
    c.domain_from_scene = true;
    for (const geometry::Phase& p : scene.phases) c.phase_names.emplace_back(p.id, p.name);
    if (!s.scene->void_note.empty()) c.notes.push_back(s.scene->void_note);
  }
  c.notes.push_back("read piece by piece: " + std::to_string(s.pieces) + " pieces, the largest " +
                    std::to_string(s.largest_piece) + " cells; " + std::to_string(s.shared.size()) +
                    " nodes in more than one piece, " + std::to_string(s.shared_facets.size()) +
                    " uses of facets between pieces checked across them");
  return c;
}

template class PiecewiseCertifier<2>;
template class PiecewiseCertifier<3>;

}  // namespace cisamr::quality
