#pragma once
// The rules every written periodic constraint must satisfy (docs/periodic-design.md §5),
// checked from the written files alone: the .inp text is parsed here (not by lib/io), the
// .msh and .vtu through io::read_mesh. Expected slaves and masters come from coordinates
// compared with the face box, never from the writer's links.
#include <gtest/gtest.h>

#include <array>
#include <cstdlib>
#include <cstring>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "io/mesh_io.hpp"

namespace cisamr::io::testing {

// What a .inp file says, parsed independently of lib/io.
struct InpFile {
  std::map<long long, std::vector<double>> nodes;  // every *NODE line, REF nodes included
  std::map<std::string, std::vector<long long>> nsets;
  struct Term {
    long long node = 0;
    int dof = 0;
    double coefficient = 0;
  };
  std::vector<std::vector<Term>> equations;
  int most_terms_on_a_line = 0;
  std::vector<std::string> comments;
  std::vector<std::string> problems;  // syntax the rules do not allow
};

inline std::vector<std::string> split_fields(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream in(line);
  std::string field;
  while (std::getline(in, field, ',')) {
    const auto b = field.find_first_not_of(" \t\r"), e = field.find_last_not_of(" \t\r");
    if (b != std::string::npos) out.push_back(field.substr(b, e - b + 1));
  }
  return out;
}

inline InpFile parse_inp(const std::string& text) {
  InpFile f;
  std::stringstream in(text);
  std::string line, keyword, nset;
  long long expected_terms = -1;  // in an *EQUATION: terms still to read, or -1 for a count line
  while (std::getline(in, line)) {
    if (line.rfind("**", 0) == 0) {
      f.comments.push_back(line);
      continue;
    }
    if (line.empty()) continue;
    if (line[0] == '*') {
      const std::vector<std::string> fields = split_fields(line.substr(1));
      keyword = fields.empty() ? "" : fields[0];
      nset.clear();
      for (const std::string& p : fields)
        if (p.rfind("NSET=", 0) == 0) nset = p.substr(5);
      if (keyword == "NSET") f.nsets[nset];
      if (expected_terms > 0) f.problems.push_back("an equation ends early");
      expected_terms = -1;
      continue;
    }
    const std::vector<std::string> fields = split_fields(line);
    if (keyword == "NODE") {
      std::vector<double> x;
      for (std::size_t k = 1; k < fields.size(); ++k) x.push_back(std::strtod(fields[k].c_str(), nullptr));
      f.nodes[std::atoll(fields[0].c_str())] = x;
    } else if (keyword == "NSET") {
      for (const std::string& id : fields) f.nsets[nset].push_back(std::atoll(id.c_str()));
    } else if (keyword == "EQUATION") {
      if (expected_terms <= 0) {
        if (fields.size() != 1) f.problems.push_back("an equation's count line holds " + line);
        expected_terms = std::atoll(fields[0].c_str());
        f.equations.emplace_back();
        continue;
      }
      if (fields.size() % 3 != 0) f.problems.push_back("a term line that is not triples: " + line);
      const int terms = static_cast<int>(fields.size() / 3);
      f.most_terms_on_a_line = std::max(f.most_terms_on_a_line, terms);
      for (int t = 0; t < terms; ++t)
        f.equations.back().push_back({std::atoll(fields[3 * t].c_str()), std::atoi(fields[3 * t + 1].c_str()),
                                      std::strtod(fields[3 * t + 2].c_str(), nullptr)});
      expected_terms -= terms;
      if (expected_terms < 0) f.problems.push_back("more terms than the count: " + line);
    }
  }
  if (expected_terms > 0) f.problems.push_back("the last equation ends early");
  return f;
}

inline bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Bit a: the point lies on the max face of periodic axis a.
template <int Dim>
unsigned shift_of(const double* x, const Box<Dim>& faces, const std::array<bool, Dim>& axes) {
  unsigned s = 0;
  for (int a = 0; a < Dim; ++a)
    if (axes[a] && x[a] == faces.max[a]) s |= 1u << a;
  return s;
}

// Whether master m is slave s moved to the min face along the axes of `shift`: there
// x_m = min and fl(x_m + T) == x_s; elsewhere bit-equal.
template <int Dim>
bool is_translate(const double* s, const double* m, unsigned shift, const Box<Dim>& faces,
                  const std::array<double, Dim>& period) {
  for (int a = 0; a < Dim; ++a) {
    if ((shift >> a) & 1) {
      if (!(m[a] == faces.min[a] && m[a] + period[a] == s[a])) return false;
    } else if (!same_bits(m[a], s[a])) {
      return false;
    }
  }
  return true;
}

struct InpSummary {
  std::size_t slaves = 0, equations = 0, corner_equations = 0;
};

// Every rule of §5 on a written .inp: `nodes` mesh nodes (ids 1..nodes), the face box,
// the periodic axes and their periods.
template <int Dim>
InpSummary check_inp_rules(const std::string& text, std::size_t nodes, const Box<Dim>& faces,
                           const std::array<bool, Dim>& axes, const std::array<double, Dim>& period) {
  const InpFile f = parse_inp(text);
  InpSummary summary;
  std::vector<std::string> errors = f.problems;
  const auto fail = [&](const std::string& what) {
    if (errors.size() < 20) errors.push_back(what);
  };
  const auto coords = [&](long long id) -> const double* {
    const auto it = f.nodes.find(id);
    if (it == f.nodes.end() || it->second.size() != static_cast<std::size_t>(Dim)) return nullptr;
    return it->second.data();
  };
  // REF nodes: one per periodic axis, ids n+1 ... in axis order, at the max corner.
  std::map<long long, int> ref_axis;
  long long next_ref = static_cast<long long>(nodes);
  for (int a = 0; a < Dim; ++a) {
    const std::string name = std::string("REF_") + "XYZ"[a];
    const auto it = f.nsets.find(name);
    if (!axes[a]) {
      if (it != f.nsets.end()) fail(name + " on a non-periodic axis");
      continue;
    }
    if (it == f.nsets.end() || it->second.size() != 1) {
      fail(name + " missing or not alone in its set");
      continue;
    }
    const long long id = it->second[0];
    if (id != ++next_ref) fail(name + " is node " + std::to_string(id) + ", not " + std::to_string(next_ref));
    ref_axis[id] = a;
    const double* x = coords(id);
    if (!x) {
      fail(name + " has no *NODE line");
      continue;
    }
    for (int d = 0; d < Dim; ++d)
      if (!same_bits(x[d], faces.max[d])) fail(name + " is not at the max corner");
  }
  if (f.nodes.size() != nodes + ref_axis.size()) fail("node count " + std::to_string(f.nodes.size()));
  // Expected slaves, from coordinates.
  std::map<long long, unsigned> slave_shift;
  for (long long id = 1; id <= static_cast<long long>(nodes); ++id) {
    const double* x = coords(id);
    if (!x) {
      fail("node " + std::to_string(id) + " missing");
      continue;
    }
    const unsigned s = shift_of<Dim>(x, faces, axes);
    if (s) slave_shift[id] = s;
  }
  summary.slaves = slave_shift.size();
  summary.equations = f.equations.size();
  if (f.most_terms_on_a_line > 4) fail("a data line holds " + std::to_string(f.most_terms_on_a_line) + " terms");
  std::set<std::pair<long long, int>> first_terms;
  std::set<long long> first_nodes, later_nodes;
  for (const auto& eq : f.equations) {
    if (eq.size() < 2) {
      fail("an equation of fewer than 2 terms");
      continue;
    }
    const int d = eq[0].dof;
    for (const auto& t : eq)
      if (t.dof != d || d < 1 || d > Dim) fail("an equation mixes dofs or names dof " + std::to_string(t.dof));
    if (eq[0].coefficient != 1.0 || eq[1].coefficient != -1.0) fail("coefficients of s and m are not 1, -1");
    if (!first_terms.insert({eq[0].node, d}).second) fail("node " + std::to_string(eq[0].node) + " dof " + std::to_string(d) + " is eliminated twice");
    first_nodes.insert(eq[0].node);
    for (std::size_t k = 1; k < eq.size(); ++k) later_nodes.insert(eq[k].node);
    const auto slave = slave_shift.find(eq[0].node);
    if (slave == slave_shift.end()) {
      fail("first term " + std::to_string(eq[0].node) + " is not on a periodic max face");
      continue;
    }
    const unsigned shift = slave->second;
    unsigned refs = 0;
    for (std::size_t k = 2; k < eq.size(); ++k) {
      const auto r = ref_axis.find(eq[k].node);
      if (r == ref_axis.end() || eq[k].coefficient != -1.0) {
        fail("term " + std::to_string(k + 1) + " of node " + std::to_string(eq[0].node) + "'s equation is not a REF node with -1");
        continue;
      }
      if ((refs >> r->second) & 1) fail("a REF node twice in one equation");
      refs |= 1u << r->second;
    }
    if (refs != shift) fail("node " + std::to_string(eq[0].node) + ": REF terms are not its shifted axes");
    if (eq.size() > 3) ++summary.corner_equations;
    const double* s = coords(eq[0].node);
    const double* m = coords(eq[1].node);
    if (!m || eq[1].node > static_cast<long long>(nodes)) {
      fail("master " + std::to_string(eq[1].node) + " is not a mesh node");
      continue;
    }
    if (shift_of<Dim>(m, faces, axes) != 0) fail("master " + std::to_string(eq[1].node) + " lies on a periodic max face");
    if (!is_translate<Dim>(s, m, shift, faces, period))
      fail("master " + std::to_string(eq[1].node) + " is not the translate of slave " + std::to_string(eq[0].node));
  }
  for (const auto& [id, shift] : slave_shift)
    for (int d = 1; d <= Dim; ++d)
      if (!first_terms.count({id, d})) fail("slave " + std::to_string(id) + " dof " + std::to_string(d) + " has no equation");
  for (long long id : first_nodes)
    if (later_nodes.count(id)) fail("node " + std::to_string(id) + " is eliminated and also appears as a later term");
  if (summary.equations != summary.slaves * Dim) fail("equation count " + std::to_string(summary.equations));
  bool documented = false;
  for (const std::string& c : f.comments) documented = documented || c.find("never a slave") != std::string::npos;
  if (!ref_axis.empty() && !documented) fail("no comment telling what to constrain");
  EXPECT_TRUE(errors.empty()) << errors.size() << " problems, first: " << (errors.empty() ? "" : errors.front());
  return summary;
}

template <int Dim>
const mesh::SimplexMesh<Dim>& mesh_of(const LoadedMesh& l) {
  if constexpr (Dim == 2) return l.mesh2;
  else return l.mesh3;
}

// A .msh read back: one $Periodic link per periodic axis from the max face entity to the
// min face entity, the affine map, and every node of the slave face with its translate.
template <int Dim>
std::size_t check_msh_links(const LoadedMesh& l, const Box<Dim>& faces, const std::array<bool, Dim>& axes,
                            const std::array<double, Dim>& period) {
  const mesh::SimplexMesh<Dim>& m = mesh_of<Dim>(l);
  std::size_t pairs = 0;
  int expected_links = 0;
  for (int a = 0; a < Dim; ++a) expected_links += axes[a];
  EXPECT_EQ(static_cast<int>(l.periodic_links.size()), expected_links);
  for (const LoadedMesh::PeriodicLink& link : l.periodic_links) {
    const int a = (link.entity - 2) / 2;
    EXPECT_EQ(link.entity_dimension, Dim - 1);
    EXPECT_EQ(link.entity, 2 * a + 2);
    EXPECT_EQ(link.master_entity, 2 * a + 1);
    if (!(a >= 0 && a < Dim && axes[a]) || link.affine.size() != 16u) {
      ADD_FAILURE() << "link of entity " << link.entity << " with " << link.affine.size() << " affine values";
      continue;
    }
    for (int i = 0; i < 16; ++i)
      EXPECT_EQ(link.affine[i], i == 4 * a + 3 ? period[a] : (i / 4 == i % 4 ? 1.0 : 0.0)) << "affine " << i;
    std::set<LocalId> slaves;
    for (std::size_t n = 0; n < m.node_count(); ++n)
      if (m.coords[n * Dim + a] == faces.max[a]) slaves.insert(static_cast<LocalId>(n));
    std::set<LocalId> seen;
    int bad = 0;
    for (const auto& [s, master] : link.nodes) {
      seen.insert(s);
      if (!is_translate<Dim>(&m.coords[static_cast<std::size_t>(s) * Dim], &m.coords[static_cast<std::size_t>(master) * Dim],
                             1u << a, faces, period))
        ++bad;
    }
    EXPECT_EQ(bad, 0) << "axis " << a;
    EXPECT_EQ(seen.size(), link.nodes.size()) << "a slave listed twice";
    EXPECT_TRUE(seen == slaves) << "axis " << a << ": " << seen.size() << " slaves listed, " << slaves.size() << " on the face";
    pairs += link.nodes.size();
  }
  return pairs;
}

// A .vtu read back: periodic_master is the full master's global id on every periodic max
// face node, -1 elsewhere.
template <int Dim>
std::size_t check_vtu_masters(const LoadedMesh& l, const Box<Dim>& faces, const std::array<bool, Dim>& axes,
                              const std::array<double, Dim>& period) {
  const mesh::SimplexMesh<Dim>& m = mesh_of<Dim>(l);
  EXPECT_EQ(l.periodic_master.size(), m.node_count());
  if (l.periodic_master.size() != m.node_count()) return 0;
  std::map<GlobalId, std::size_t> by_gid;
  for (std::size_t n = 0; n < m.node_count(); ++n) by_gid[m.node_global_id.empty() ? GlobalId(n) : m.node_global_id[n]] = n;
  std::size_t slaves = 0;
  int bad = 0;
  for (std::size_t n = 0; n < m.node_count(); ++n) {
    const unsigned shift = shift_of<Dim>(&m.coords[n * Dim], faces, axes);
    const GlobalId g = l.periodic_master[n];
    if (shift == 0) {
      bad += g != -1;
      continue;
    }
    ++slaves;
    const auto it = by_gid.find(g);
    if (it == by_gid.end()) {
      ++bad;
      continue;
    }
    const double* x = &m.coords[it->second * Dim];
    bad += shift_of<Dim>(x, faces, axes) != 0 || !is_translate<Dim>(&m.coords[n * Dim], x, shift, faces, period);
  }
  EXPECT_EQ(bad, 0);
  return slaves;
}

}  // namespace cisamr::io::testing
