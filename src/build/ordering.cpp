// Build steps for the unknowns (build/build_steps.h): the length scale, the layout of the
// unknowns and multipliers, and the solver ordering with its band pattern.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "build_steps.h"
#include "screwfem/build/model_builder.h"
#include "screwfem/elements/joint.h"
#include "screwfem/elements/registry.h"
#include "screwfem/linalg/banded_lu.h"
#include "screwfem/model/data.h"
#include "screwfem/model/errors.h"

namespace screwfem::build_steps {

void SetLengthScale(Model& m) {
  const int num_nodes = static_cast<int>(m.nodes.size());
  // Characteristic length: the diagonal of the bounding box of all node positions.
  Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
  for (const Node& n : m.nodes) {
    lo = lo.cwiseMin(n.reference.x);
    hi = hi.cwiseMax(n.reference.x);
  }
  m.length_scale = num_nodes > 0 ? std::max((hi - lo).norm(), 1e-3) : 1.0;
  for (const Rod& r : m.rods) m.length_scale = std::max(m.length_scale, r.length);
}

// Unknowns: 6 velocities per free node, then the joints' coordinates; multipliers: 6 rows per
// constrained joint and one per prescribed drive.
void LayOutUnknowns(Model& m) {
  m.nv = 0;
  for (Node& n : m.nodes) {
    n.dof = n.fixed ? -1 : m.nv;
    if (!n.fixed) m.nv += 6;
  }
  m.nv_nodes = m.nv;
  m.nc = 0;
  for (Joint& j : m.joints) {
    j.coord = m.nv;
    m.nv += j.k();
    j.row = -1;
    if (GetJointTypeInfo(j.type).constrained) {
      j.row = m.nc;
      m.nc += 6;
    }
    j.drive_row = -1;
    if (j.drive == DriveKind::kPrescribed) {
      j.drive_row = m.nc;
      m.nc += 1;
    }
  }
  // One row per length-driven tendon, after the joints' rows.
  for (Tendon& t : m.tendons) {
    t.row = -1;
    if (t.drive == TendonDrive::kLength) t.row = m.nc++;
  }
}

namespace {

// Block graph: a block is a contiguous range of unknowns that always couple together; an
// edge is a block of the iteration matrix that the assembly writes (rod elements couple
// their nodes, joints their constraint rows with both nodes and their coordinates, drives
// their row with the coordinates). The term d(B^T lambda)/dq, which would couple the two
// nodes of a joint, is not assembled (docs/architecture.md, "One time step"). The permuted matrix has these blocks
// only: model.pattern_last, checked by the assembly. Blocks are numbered in the order they are
// added: the free nodes' (NodeBlocks), then the constraint kinds' coordinates and rows in the
// order of the rows (AddConstraintBlocks).
struct BlockGraph {
  struct Block {
    int start, size;
  };
  std::vector<Block> blocks;
  std::vector<int> node_block;  // per node: its block, -1 for a fixed node
  std::vector<std::pair<int, int>> edges;

  int Add(int start, int size) {
    blocks.push_back({start, size});
    return static_cast<int>(blocks.size()) - 1;
  }
  // An edge between two blocks; none when either is -1 (the ground, a fixed node, no block)
  // or for a block with itself.
  void Link(int a, int b) {
    if (a >= 0 && b >= 0 && a != b) edges.emplace_back(a, b);
  }
  int OfNode(int node) const {
    return node == kGround ? -1 : node_block[static_cast<std::size_t>(node)];
  }
};

// One block of 6 velocities per free node, in node order.
BlockGraph NodeBlocks(const Model& m) {
  const int num_nodes = static_cast<int>(m.nodes.size());
  BlockGraph g;
  g.node_block.assign(static_cast<std::size_t>(num_nodes), -1);
  for (int n = 0; n < num_nodes; ++n) {
    const Node& node = m.nodes[static_cast<std::size_t>(n)];
    if (node.fixed) continue;
    g.node_block[static_cast<std::size_t>(n)] = static_cast<int>(g.blocks.size());
    g.blocks.push_back({node.dof, 6});
  }
  return g;
}

// Every item of every element kind couples its nodes with each other: the kinds' own lists
// of items and nodes (elements/registry.h: rod elements, tendon segments, force elements, the
// springs of free joints, ...), so a new kind needs no code here. The kinds whose items are
// found during the run (the pairs of the contact broad phase) are linked by
// LinkContactEntities.
void LinkElementNodes(const Model& m, BlockGraph& g) {
  ForEachKind<ElementKinds>([&]<class Kind>() {
    if constexpr (!requires { Kind::kItemsInData; }) {
      constexpr int N = Kind::kNodes;
      Kind::ForEach(m, [&](const typename Kind::Item&, const int(&nodes)[N]) {
        for (int i = 0; i < N; ++i)
          for (int j = i + 1; j < N; ++j) g.Link(g.OfNode(nodes[i]), g.OfNode(nodes[j]));
      });
    }
  });
}

// A pair of moving shapes couples the nodes of its two sides (elements/shape_pair.h). Two
// entities that may touch (or a rod that may touch itself) are linked here, every node of one
// with every node of the other, when the product of their node counts is at most
// ContactSettings::band_pair_nodes (bodies, short rods: the band has room for the coupling);
// the couplings of the others that fall outside the band enter the banded solve as a low-rank
// update (Data::coupling), so that long rods do not widen the band. When these links number
// more than kMaxBandContactLinks in all (thousands of bodies that may touch each other), none
// is made. The sparse LU takes none of these links: its pattern gets the blocks of the pairs
// the broad phase finds (SelectSparsePattern), so the links are the edges [edges_begin,
// edges_end) of g, left out of its pattern.
struct ContactLinks {
  std::size_t edges_begin = 0, edges_end = 0;
  // Nodes of the entities that may touch one they are not linked with: at most this many
  // nodes can enter the banded solve's off-band coupling at once.
  int off_band_nodes = 0;
  // The nodes predicted in that coupling at once: per pair of such entities (a rod with
  // itself), up to kContactRegionNodes of each (Model::coupled_nodes), at most off_band_nodes.
  double region_nodes = 0.0;
  std::string warning;  // for the banded LU: the links were too many to make
};
ContactLinks LinkContactEntities(Model& m, BlockGraph& g) {
  ContactLinks out;
  out.edges_begin = out.edges_end = g.edges.size();
  const int ne = m.num_contact_entities;
  // Per entity: its nodes with unknowns, sorted and unique.
  std::vector<std::vector<int>> entity_nodes(static_cast<std::size_t>(ne));
  for (const ContactSegment& s : m.contact_segments)
    for (int k : s.side.node)
      if (g.OfNode(k) >= 0) entity_nodes[static_cast<std::size_t>(s.entity)].push_back(k);
  for (std::vector<int>& list : entity_nodes) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  const auto touch = [&](int a, int b) {
    return a == b ? m.contact_entity_self_skip[static_cast<std::size_t>(a)] >= 0.0
                  : m.contact_entity_pairs.MayTouch(a, b);
  };
  const auto linked = [&](int a, int b) {
    const double links = static_cast<double>(entity_nodes[static_cast<std::size_t>(a)].size()) *
                         static_cast<double>(entity_nodes[static_cast<std::size_t>(b)].size());
    return touch(a, b) && links <= static_cast<double>(m.contact.band_pair_nodes) ? links : 0.0;
  };
  // The links first: beyond kMaxBandContactLinks in all, none goes in the band.
  double total = 0.0;
  long pairs = 0;
  for (int a = 0; a < ne; ++a)
    for (int b = a; b < ne; ++b) {
      const double links = linked(a, b);
      total += links;
      pairs += links > 0.0 ? 1 : 0;
    }
  const bool none = total > kMaxBandContactLinks;
  // The nodes that may enter the off-band coupling: those of an entity that may touch one it
  // is not linked with.
  std::vector<char> off_band(static_cast<std::size_t>(ne), 0);
  const auto region = [&](int a) {
    return std::min(static_cast<double>(entity_nodes[static_cast<std::size_t>(a)].size()),
                    static_cast<double>(kContactRegionNodes));
  };
  for (int a = 0; a < ne; ++a)
    for (int b = a; b < ne; ++b)
      if (touch(a, b) && (none || linked(a, b) == 0.0)) {
        off_band[static_cast<std::size_t>(a)] = off_band[static_cast<std::size_t>(b)] = 1;
        out.region_nodes += region(a) + region(b);
      }
  for (int a = 0; a < ne; ++a)
    if (off_band[static_cast<std::size_t>(a)])
      out.off_band_nodes += static_cast<int>(entity_nodes[static_cast<std::size_t>(a)].size());
  out.region_nodes = std::min(out.region_nodes, static_cast<double>(out.off_band_nodes));
  if (none) {
    char text[320];
    std::snprintf(text, sizeof text,
                  "the %ld pairs of contact entities that may touch would couple %.0f node "
                  "pairs in the solver's band (more than %.0f): they are left off the band, "
                  "and those that touch enter the solve as the off-band coupling (at most %d "
                  "nodes at a time)",
                  pairs, total, kMaxBandContactLinks, kMaxCoupledNodes);
    out.warning = text;
    return out;
  }
  for (int a = 0; a < ne; ++a)
    for (int b = a; b < ne; ++b) {
      if (linked(a, b) == 0.0) continue;
      for (int x : entity_nodes[static_cast<std::size_t>(a)])
        for (int y : entity_nodes[static_cast<std::size_t>(b)]) g.Link(g.OfNode(x), g.OfNode(y));
    }
  out.edges_end = g.edges.size();
  return out;
}

// The constraint kinds (elements/registry.h): per item, a block of its rows, linked with every
// block of unknowns its rows act on (ForEachColumn: nodes, a joint's coordinates). Unknowns
// that are no node's (a joint's coordinates) become a block of their own the first time an
// item names them. Items are taken in the order of their rows (LayOutUnknowns: a joint's six
// rows and then its drive's, joint by joint, then the length-driven tendons'), so a joint's
// coordinates come just before its rows and its drive's row after them: the numbering of the
// blocks decides the ties of the ordering, and it does not depend on the order of the kinds.
void AddConstraintBlocks(const Model& m, BlockGraph& g) {
  struct Entry {
    int row, kind, item;
  };
  std::vector<Entry> entries;
  int kind = 0;
  ForEachKind<ConstraintKinds>([&]<class Kind>() {
    static_assert(std::is_same_v<typename Kind::Item, int>, "constraint items are indices");
    Kind::ForEach(m, [&](int item) {
      if (Kind::RowCount(m, item) > 0) entries.push_back({Kind::FirstRow(m, item), kind, item});
    });
    ++kind;
  });
  std::sort(entries.begin(), entries.end(),
            [](const Entry& a, const Entry& b) { return a.row < b.row; });
  // The block holding each unknown (-1: none yet); node blocks are known.
  std::vector<int> block_of(static_cast<std::size_t>(m.nv), -1);
  for (std::size_t b = 0; b < g.blocks.size(); ++b)
    for (int i = 0; i < g.blocks[b].size; ++i)
      block_of[static_cast<std::size_t>(g.blocks[b].start + i)] = static_cast<int>(b);
  std::vector<int> columns;
  for (const Entry& e : entries) {
    columns.clear();
    int k = 0;
    ForEachKind<ConstraintKinds>([&]<class Kind>() {
      if (k++ != e.kind) return;
      Kind::ForEachColumn(m, e.item, [&](int first, int size) {
        int& block = block_of[static_cast<std::size_t>(first)];
        if (block < 0) {
          block = g.Add(first, size);
          for (int i = 1; i < size; ++i) block_of[static_cast<std::size_t>(first + i)] = block;
        }
        columns.push_back(block);
      });
      const int rows = g.Add(m.nv + Kind::FirstRow(m, e.item), Kind::RowCount(m, e.item));
      for (int c : columns) g.Link(rows, c);
    });
  }
  // Unknowns no row acts on (none today: every joint with coordinates has rows) still need a
  // place in the ordering.
  for (int i = 0; i < m.nv; ++i)
    if (block_of[static_cast<std::size_t>(i)] < 0)
      block_of[static_cast<std::size_t>(i)] = g.Add(i, 1);
}

// The neighbours of every block, sorted and without repeats; without the edges [skip_begin,
// skip_end) of g.
std::vector<std::vector<int>> BlockAdjacency(const BlockGraph& g, std::size_t skip_begin = 0,
                                             std::size_t skip_end = 0) {
  std::vector<std::vector<int>> adj(g.blocks.size());
  for (std::size_t e = 0; e < g.edges.size(); ++e) {
    if (e >= skip_begin && e < skip_end) continue;
    const auto& [a, b] = g.edges[e];
    adj[static_cast<std::size_t>(a)].push_back(b);
    adj[static_cast<std::size_t>(b)].push_back(a);
  }
  for (auto& list : adj) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  return adj;
}

// Orders the blocks by reverse Cuthill-McKee and numbers their unknowns consecutively in that
// order (Model::permutation: unknown -> position); returns each block's first position.
std::vector<int> PermuteBlocks(Model& m, const BlockGraph& g,
                               const std::vector<std::vector<int>>& adj) {
  const std::vector<int> block_perm = ReverseCuthillMcKee(adj);
  std::vector<int> order(g.blocks.size());
  for (std::size_t b = 0; b < g.blocks.size(); ++b)
    order[static_cast<std::size_t>(block_perm[b])] = static_cast<int>(b);
  m.permutation.assign(static_cast<std::size_t>(m.num_unknowns()), -1);
  std::vector<int> block_pos(g.blocks.size());
  int pos = 0;
  for (int b : order) {
    block_pos[static_cast<std::size_t>(b)] = pos;
    const BlockGraph::Block& blk = g.blocks[static_cast<std::size_t>(b)];
    for (int i = 0; i < blk.size; ++i)
      m.permutation[static_cast<std::size_t>(blk.start + i)] = pos++;
  }
  SCREWFEM_CHECK(pos == m.num_unknowns());
  return block_pos;
}

// The band pattern of the permuted matrix: Model::bandwidth, and per row the last column of
// the blocks its block couples with (Model::pattern_last).
void SetBandPattern(Model& m, const BlockGraph& g, const std::vector<std::vector<int>>& adj,
                    const std::vector<int>& block_pos) {
  const std::vector<BlockGraph::Block>& blocks = g.blocks;
  m.bandwidth = 0;
  m.pattern_last.assign(static_cast<std::size_t>(m.num_unknowns()), 0);
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    m.bandwidth = std::max(m.bandwidth, blocks[b].size - 1);
    int last = block_pos[b] + blocks[b].size - 1;
    for (int c : adj[b]) {
      const int lo = std::min(block_pos[b], block_pos[static_cast<std::size_t>(c)]);
      const int hi =
          std::max(block_pos[b] + blocks[b].size, block_pos[static_cast<std::size_t>(c)] +
                                                      blocks[static_cast<std::size_t>(c)].size);
      m.bandwidth = std::max(m.bandwidth, hi - 1 - lo);
      last = std::max(last, block_pos[static_cast<std::size_t>(c)] +
                                blocks[static_cast<std::size_t>(c)].size - 1);
    }
    for (int i = 0; i < blocks[b].size; ++i)
      m.pattern_last[static_cast<std::size_t>(block_pos[b] + i)] = last;
  }
}

// The sparse pattern (Model::sparse_pattern: every block with itself and with each neighbour
// in `adj`, the graph without the contact links) and the choice of the solver: the predicted
// flops of one factorisation by each. The banded LU eliminates inside the envelope of
// pattern_last (row interchanges may widen it; not counted): column j updates (last_j - j)^2
// entries, a multiply and a subtraction each. KLU's estimate comes from its symbolic analysis
// (AMD's count of the LU on its ordering). `auto` takes the sparse LU also when more nodes may
// be coupled off the band than the banded solve's coupling holds (kMaxCoupledNodes): beyond
// that room its iteration would become quasi-Newton, while the sparse pattern takes every
// pair.
void ChooseSolver(Model& m, const BlockGraph& g, const std::vector<std::vector<int>>& adj,
                  const std::vector<int>& block_pos, const ContactLinks& contact) {
  m.sparse_pattern.clear();
  for (std::size_t b = 0; b < g.blocks.size(); ++b) {
    const int pb = block_pos[b], sb = g.blocks[b].size;
    m.sparse_pattern.push_back({pb, sb, pb, sb});
    for (int c : adj[b])
      m.sparse_pattern.push_back({pb, sb, block_pos[static_cast<std::size_t>(c)],
                                  g.blocks[static_cast<std::size_t>(c)].size});
  }
  m.banded_flops = 0.0;
  double envelope = 0.0;  // the entries below the diagonal in the envelope
  for (int j = 0; j < m.num_unknowns(); ++j) {
    const double r = m.pattern_last[static_cast<std::size_t>(j)] - j;
    m.banded_flops += 2.0 * r * r + r;
    envelope += r;
  }
  // The Woodbury coupling of the contact pairs predicted at once (BandCoupling::Factorize):
  // k banded solves (forward and back through the envelope, a multiply and an add per
  // entry) and the dense LU of k x k.
  m.coupled_nodes = static_cast<int>(std::min(contact.region_nodes, double{kMaxCoupledNodes}));
  const double k = 6.0 * m.coupled_nodes;
  m.coupling_flops =
      k > 0.0 ? k * (4.0 * envelope + 2.0 * m.num_unknowns()) + 2.0 / 3.0 * k * k * k : 0.0;
  const double banded_cost = PredictedBandedCost(m);
  m.sparse_flops = m.sparse_factor_nonzeros = 0.0;
  // A pattern that fills a quarter of the matrix or more (hundreds of bodies that may all
  // touch each other, linked in the pattern) gains nothing from a sparse LU: auto does not
  // analyse it (an analysis of tens of millions of entries).
  double entries = 0.0;
  for (const SparseLU::Block& b : m.sparse_pattern)
    entries += static_cast<double>(b.rows) * static_cast<double>(b.cols);
  const double n = m.num_unknowns();
  // Nor a band so narrow that the sparse LU's least cost (its fixed cost per unknown, and the
  // LU of the 6 x 6 diagonal blocks alone, 24 flops per unknown) exceeds the band's: rods and
  // chains need no analysis (a rod of 100,000 elements: 600,000 unknowns).
  const bool narrow = banded_cost < (kSparseFixedCost + kSparseFlopCost * 24.0) * n;
  const bool contact_room = contact.off_band_nodes > kMaxCoupledNodes;
  const bool skip = m.linear_solver == LinearSolver::kAuto && !contact_room &&
                    ((entries > 0.25 * n * n && n > 64) || narrow);
  if (m.linear_solver != LinearSolver::kBanded && m.num_unknowns() > 0 && !skip) {
    SparseLU lu;
    lu.SetPattern(m.num_unknowns(), m.sparse_pattern);
    m.sparse_flops = lu.predicted_flops();
    m.sparse_factor_nonzeros = lu.predicted_factor_nonzeros();
  }
  m.sparse_solver =
      m.linear_solver == LinearSolver::kSparse ||
      (m.linear_solver == LinearSolver::kAuto && !skip &&
       (contact_room ||
        kSparseFlopCost * m.sparse_flops + kSparseFixedCost * m.num_unknowns() < banded_cost));
  if (!m.sparse_solver) std::vector<SparseLU::Block>().swap(m.sparse_pattern);
  if (!m.sparse_solver && !contact.warning.empty()) m.warnings.push_back(contact.warning);
}

}  // namespace

// The solver ordering: the block graph of the iteration matrix (BlockGraph: nodes, the
// couplings of elements, contact, joints and length-driven tendons), its reverse Cuthill-McKee
// order, and the band pattern that order implies.
void OrderUnknowns(Model& m) {
  BlockGraph g = NodeBlocks(m);
  LinkElementNodes(m, g);
  const ContactLinks contact = LinkContactEntities(m, g);
  AddConstraintBlocks(m, g);
  const std::vector<std::vector<int>> adj = BlockAdjacency(g);
  const std::vector<int> block_pos = PermuteBlocks(m, g, adj);
  SetBandPattern(m, g, adj, block_pos);
  if (contact.edges_end > contact.edges_begin)
    ChooseSolver(m, g, BlockAdjacency(g, contact.edges_begin, contact.edges_end), block_pos,
                 contact);
  else
    ChooseSolver(m, g, adj, block_pos, contact);
}

}  // namespace screwfem::build_steps
