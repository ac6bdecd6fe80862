// Build steps for the unknowns (build/build_steps.h): the length scale, the layout of the
// unknowns and multipliers, and the solver ordering with its band pattern.
#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "build_steps.h"
#include "screwfem/elements/joint.h"
#include "screwfem/linalg/banded_lu.h"
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
// nodes of a joint, is not assembled (method.md §5.2). The permuted matrix has these blocks
// only: model.pattern_last, checked by the assembly. Blocks are numbered in the order they are
// added: the free nodes' (NodeBlocks), then the joints' (AddJointBlocks), then the
// length-driven tendons' rows (AddTendonRowBlocks).
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

// Rod elements couple their nodes.
// Tendon segments and force elements couple their two nodes (elements/tendon.h).
// An eyelet between nodes brings both nodes of its element.
void LinkElementNodes(const Model& m, BlockGraph& g) {
  for (const RodElement& e : m.elements) g.Link(g.OfNode(e.node_a), g.OfNode(e.node_b));
  for (const TendonSegment& s : m.tendon_segments) {
    auto node_b = [&](const BodyPoint& p) {
      return p.element >= 0 ? m.elements[static_cast<std::size_t>(p.element)].node_b : kGround;
    };
    const int nodes[4] = {s.a.node, node_b(s.a), s.b.node, node_b(s.b)};
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) g.Link(g.OfNode(nodes[i]), g.OfNode(nodes[j]));
  }
  for (const ForceElement& f : m.force_elements) g.Link(g.OfNode(f.a.node), g.OfNode(f.b.node));
}

// A pair of moving shapes couples the nodes of its two sides (elements/shape_pair.h). Two
// entities that may touch (or a rod that may touch itself) are linked here, every node of one
// with every node of the other, when the product of their node counts is at most
// ContactSettings::band_pair_nodes (bodies, short rods: the band has room for the coupling);
// the couplings of the others that fall outside the band enter the solve as a low-rank
// update (Data::coupling), so that long rods do not widen the band.
void LinkContactEntities(const Model& m, BlockGraph& g) {
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
  for (int a = 0; a < ne; ++a)
    for (int b = a; b < ne; ++b) {
      const bool touch = a == b ? m.contact_entity_self_skip[static_cast<std::size_t>(a)] >= 0.0
                                : m.contact_entity_pairs[static_cast<std::size_t>(a * ne + b)] != 0;
      const std::vector<int>& na = entity_nodes[static_cast<std::size_t>(a)];
      const std::vector<int>& nbs = entity_nodes[static_cast<std::size_t>(b)];
      if (!touch || static_cast<double>(na.size()) * static_cast<double>(nbs.size()) >
                        static_cast<double>(m.contact.band_pair_nodes))
        continue;
      for (int x : na)
        for (int y : nbs) g.Link(g.OfNode(x), g.OfNode(y));
    }
}

// Per joint: a block of its coordinates; a block of its 6 constraint rows, coupled with both
// nodes and the coordinates; a prescribed drive's row, coupled with the coordinates.
void AddJointBlocks(const Model& m, BlockGraph& g) {
  for (const Joint& j : m.joints) {
    const int coord_block = j.k() > 0 ? g.Add(j.coord, j.k()) : -1;
    if (j.row >= 0) {
      const int cb = g.Add(m.nv + j.row, 6);
      g.Link(cb, g.OfNode(j.node_a));
      g.Link(cb, g.OfNode(j.node_b));
      g.Link(cb, coord_block);
    }
    // A joint whose springs act on the nodes' relative motion (a free joint) couples them.
    if (GetJointTypeInfo(j.type).spring_law == JointSpringLaw::kRelativeMotion)
      g.Link(g.OfNode(j.node_a), g.OfNode(j.node_b));
    if (j.drive_row >= 0) g.Link(g.Add(m.nv + j.drive_row, 1), coord_block);
  }
}

// A length-driven tendon's row couples with every eyelet's node (a band as wide as the
// tendon's route in the ordering; docs/numerics.md).
void AddTendonRowBlocks(const Model& m, BlockGraph& g) {
  for (const Tendon& t : m.tendons) {
    if (t.row < 0) continue;
    const int tb = g.Add(m.nv + t.row, 1);
    for (const BodyPoint& e : t.eyelets) {
      g.Link(tb, g.OfNode(e.node));
      if (e.element >= 0)
        g.Link(tb, g.OfNode(m.elements[static_cast<std::size_t>(e.element)].node_b));
    }
  }
}

// The neighbours of every block, sorted and without repeats.
std::vector<std::vector<int>> BlockAdjacency(const BlockGraph& g) {
  std::vector<std::vector<int>> adj(g.blocks.size());
  for (const auto& [a, b] : g.edges) {
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
    for (int i = 0; i < blk.size; ++i) m.permutation[static_cast<std::size_t>(blk.start + i)] = pos++;
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
      const int hi = std::max(block_pos[b] + blocks[b].size,
                              block_pos[static_cast<std::size_t>(c)] +
                                  blocks[static_cast<std::size_t>(c)].size);
      m.bandwidth = std::max(m.bandwidth, hi - 1 - lo);
      last = std::max(last, block_pos[static_cast<std::size_t>(c)] +
                                blocks[static_cast<std::size_t>(c)].size - 1);
    }
    for (int i = 0; i < blocks[b].size; ++i)
      m.pattern_last[static_cast<std::size_t>(block_pos[b] + i)] = last;
  }
}

}  // namespace

// The solver ordering: the block graph of the iteration matrix (BlockGraph: nodes, the
// couplings of elements, contact, joints and length-driven tendons), its reverse Cuthill-McKee
// order, and the band pattern that order implies.
void OrderUnknowns(Model& m) {
  BlockGraph g = NodeBlocks(m);
  LinkElementNodes(m, g);
  LinkContactEntities(m, g);
  AddJointBlocks(m, g);
  AddTendonRowBlocks(m, g);
  const std::vector<std::vector<int>> adj = BlockAdjacency(g);
  const std::vector<int> block_pos = PermuteBlocks(m, g, adj);
  SetBandPattern(m, g, adj, block_pos);
}

}  // namespace screwfem::build_steps
