// Redundant constraints at the reference configuration (model.h, FindRedundantConstraints).
//
// B (nc x nv) is the constraint gradient of the joint kernel (CalcJointGradient, elements/joint.h)
// at the reference state (H_J = I,
// phi = the reference residual, ~0) plus a unit row per prescribed drive. It is never formed:
// only the nodes that joints touch carry nonzero columns, and a joint's six rows touch its two
// nodes and its own coordinates.
//
// Spanning forest. Vertices: every node with unknowns, and one vertex G for the ground and all
// fixed nodes (no unknowns). Edges: joints with constraint rows. A breadth-first forest from G
// (then from every unvisited vertex: floating parts) makes every other vertex the child of one
// tree joint, whose block on that child is invertible (T^-1 Ad). Ordered by child, the tree
// rows are block-triangular: independent, and their kernel is parametrised by the coordinates
// of the tree joints and the roots' velocities: dh_c = -B_c^-1 (B_p dh_p + B_J dalpha).
// rank B = 6 (tree joints) + rank(C N), with C the chord and drive rows and N that kernel.
//
// A chord's rows applied to N involve only the tree joints between its ends and their lowest
// common ancestor: a common rigid motion of both ends leaves the relative frame, hence phi,
// unchanged (B_A dh_A + B_B dh_B = 0 for it), so the ancestor's velocity drops out exactly.
// The reduced rows are grouped by shared coordinates and each group is rank-revealed with a
// column-pivoting QR of its transpose; redundant rows are the group's last pivots.
//
// Joints involved: a dependency y (B^T y = 0) is z on chord/drive rows (a kernel vector of the
// reduced rows) and w on tree rows, found from the node balance of the child of each tree
// joint, deepest first: w_e = -B_c^-T (sum of the other rows' B^T y on node c).
#include <Eigen/LU>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <string>

#include "screwfem/build/model_builder.h"
#include "screwfem/elements/joint.h"

namespace screwfem {

namespace {

struct GraphJoint {
  int joint = -1;
  int va = -1, vb = -1;  // vertices of sides A and B
};

// Union-find over reduced rows.
int Root(std::vector<int>& parent, int i) {
  while (parent[static_cast<std::size_t>(i)] != i) {
    parent[static_cast<std::size_t>(i)] =
        parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(i)])];
    i = parent[static_cast<std::size_t>(i)];
  }
  return i;
}

// Gradient blocks of a joint at the reference state (H_J = I).
struct Blocks {
  Mat6 a, b;
  Mat6X coord;
};
Blocks ReferenceGradient(const Model& m, int jj) {
  const Joint& j = m.joints[static_cast<std::size_t>(jj)];
  JointGradient jg;
  CalcJointGradient(j, NodeReferenceFrame(m, j.node_a), NodeReferenceFrame(m, j.node_b),
                    SE3::Identity(), &jg);
  Blocks g;
  g.a = JointGradientA(jg);
  g.b = JointGradientB(jg);
  g.coord = JointGradientCoordinates(jg, j.basis, JointMatrix::Identity(j.k(), j.k()));
  return g;
}

// The work spent so far (kMaxRedundancyWork) and whether it passed the bound.
struct Work {
  double spent = 0.0;
  bool too_large = false;
};

// The joint graph (vertices: nodes with unknowns and the ground vertex; edges: joints with
// constraint rows) and its breadth-first spanning forest.
struct JointForest {
  int ground = -1;  // the vertex of the ground and all fixed nodes
  std::vector<GraphJoint> edges;
  std::vector<int> parent_edge, depth;  // per vertex (-1: a root, or not reached)
  std::vector<char> is_tree;            // per edge
  bool IsChord(const GraphJoint& e) const {
    return !is_tree[static_cast<std::size_t>(&e - edges.data())];
  }
  int ParentOf(int v) const {
    const GraphJoint& e = edges[static_cast<std::size_t>(parent_edge[static_cast<std::size_t>(v)])];
    return e.va == v ? e.vb : e.va;
  }
};

JointForest BuildJointForest(const Model& m) {
  JointForest f;
  const int num_nodes = static_cast<int>(m.nodes.size());
  const int G = num_nodes;
  f.ground = G;
  auto vertex = [&](int node) {
    return node == kGround || m.nodes[static_cast<std::size_t>(node)].dof < 0 ? G : node;
  };
  std::vector<GraphJoint>& edges = f.edges;
  for (std::size_t jj = 0; jj < m.joints.size(); ++jj) {
    const Joint& j = m.joints[jj];
    if (j.row >= 0) edges.push_back({static_cast<int>(jj), vertex(j.node_a), vertex(j.node_b)});
  }
  const std::size_t nvert = static_cast<std::size_t>(num_nodes) + 1;
  std::vector<int> adj_start(nvert + 1, 0), adj;
  for (const GraphJoint& e : edges) {
    ++adj_start[static_cast<std::size_t>(e.va) + 1];
    if (e.vb != e.va) ++adj_start[static_cast<std::size_t>(e.vb) + 1];
  }
  for (std::size_t v = 0; v < nvert; ++v) adj_start[v + 1] += adj_start[v];
  adj.resize(static_cast<std::size_t>(adj_start[nvert]));
  {
    std::vector<int> fill(adj_start.begin(), adj_start.end() - 1);
    for (std::size_t e = 0; e < edges.size(); ++e) {
      adj[static_cast<std::size_t>(fill[static_cast<std::size_t>(edges[e].va)]++)] =
          static_cast<int>(e);
      if (edges[e].vb != edges[e].va)
        adj[static_cast<std::size_t>(fill[static_cast<std::size_t>(edges[e].vb)]++)] =
            static_cast<int>(e);
    }
  }
  f.parent_edge.assign(nvert, -1);
  f.depth.assign(nvert, -1);
  f.is_tree.assign(edges.size(), 0);
  std::vector<int>& parent_edge = f.parent_edge;
  std::vector<int>& depth = f.depth;
  std::vector<int> queue;
  queue.reserve(nvert);
  auto bfs = [&](int root) {
    depth[static_cast<std::size_t>(root)] = 0;
    queue.clear();
    queue.push_back(root);
    for (std::size_t q = 0; q < queue.size(); ++q) {
      const int u = queue[q];
      for (int i = adj_start[static_cast<std::size_t>(u)];
           i < adj_start[static_cast<std::size_t>(u) + 1]; ++i) {
        const int e = adj[static_cast<std::size_t>(i)];
        const int w = edges[static_cast<std::size_t>(e)].va == u
                          ? edges[static_cast<std::size_t>(e)].vb
                          : edges[static_cast<std::size_t>(e)].va;
        if (depth[static_cast<std::size_t>(w)] >= 0) continue;
        depth[static_cast<std::size_t>(w)] = depth[static_cast<std::size_t>(u)] + 1;
        parent_edge[static_cast<std::size_t>(w)] = e;
        f.is_tree[static_cast<std::size_t>(e)] = 1;
        queue.push_back(w);
      }
    }
  };
  bfs(G);
  for (int v = 0; v < num_nodes; ++v)
    if (depth[static_cast<std::size_t>(v)] < 0 &&
        adj_start[static_cast<std::size_t>(v)] < adj_start[static_cast<std::size_t>(v) + 1])
      bfs(v);
  return f;
}

// Walks from the chord's ends to their lowest common ancestor; for each tree joint on the
// way calls f(u, e, Y_u): Y_u maps dh_u to the chord rows (6 x 6), u the child of tree edge e.
// Stops when the work passes the bound.
template <class F>
void WalkChord(const Model& m, const JointForest& forest, const GraphJoint& chord, const Blocks& cg,
               Work* work, F&& f) {
  int u[2] = {chord.va, chord.vb};
  Mat6 Y[2] = {cg.a, cg.b};
  auto step = [&](int s) {
    const int e = forest.parent_edge[static_cast<std::size_t>(u[s])];
    f(u[s], e, Y[s]);
    const GraphJoint& te = forest.edges[static_cast<std::size_t>(e)];
    const Blocks tg = ReferenceGradient(m, te.joint);
    const bool child_is_a = te.va == u[s];
    const Mat6& Bc = child_is_a ? tg.a : tg.b;
    const Mat6& Bp = child_is_a ? tg.b : tg.a;
    const int p = forest.ParentOf(u[s]);
    // Y_p = -Y_u B_c^-1 B_p
    Y[s] = -(Bc.transpose().partialPivLu().solve(Y[s].transpose())).transpose() * Bp;
    u[s] = p;
    work->spent += 1.0;
  };
  while (u[0] != u[1] && !work->too_large) {
    const int side =
        forest.depth[static_cast<std::size_t>(u[0])] >= forest.depth[static_cast<std::size_t>(u[1])]
            ? 0
            : 1;
    step(side);
    if (work->spent > kMaxRedundancyWork) work->too_large = true;
  }
}

// An entry (row, column, value) of the reduced rows; columns are joint-coordinate velocity
// indices.
struct Entry {
  int row, col;
  double value;
};

// The chord rows reduced onto the coordinates of the tree joints on their paths, and the
// drive rows. Stops early when the work passes the bound.
std::vector<Entry> ReduceChordAndDriveRows(const Model& m, const JointForest& forest, Work* work) {
  std::vector<Entry> entries;
  for (const GraphJoint& chord : forest.edges) {
    if (!forest.IsChord(chord) || work->too_large) continue;
    const Joint& j = m.joints[static_cast<std::size_t>(chord.joint)];
    const Blocks cg = ReferenceGradient(m, chord.joint);
    for (int c = 0; c < j.k(); ++c)
      for (int r = 0; r < 6; ++r) entries.push_back({j.row + r, j.coord + c, cg.coord(r, c)});
    WalkChord(m, forest, chord, cg, work, [&](int u, int e, const Mat6& Yu) {
      const GraphJoint& te = forest.edges[static_cast<std::size_t>(e)];
      const Joint& tj = m.joints[static_cast<std::size_t>(te.joint)];
      if (tj.k() == 0) return;
      const Blocks tg = ReferenceGradient(m, te.joint);
      const Mat6& Bc = te.va == u ? tg.a : tg.b;
      // rows += Y_u (-B_c^-1 B_J) dalpha_e
      const Mat6X coef = -Yu * Bc.partialPivLu().solve(tg.coord);
      for (int c = 0; c < tj.k(); ++c)
        for (int r = 0; r < 6; ++r) entries.push_back({j.row + r, tj.coord + c, coef(r, c)});
    });
  }
  if (work->too_large) return entries;
  for (const Joint& j : m.joints)
    if (j.drive_row >= 0) entries.push_back({j.drive_row, j.coord + j.drive_coord, 1.0});
  return entries;
}

// The reduced rows grouped by shared coordinates (a joint's rows always together), keyed by
// a root row, with the entries of each group; row_joint: the joint of each constraint row.
struct RowGroups {
  std::map<int, std::vector<int>> rows;
  std::map<int, std::vector<const Entry*>> entries;
  std::vector<int> row_joint;
};

RowGroups GroupReducedRows(const Model& m, const JointForest& forest,
                           const std::vector<Entry>& entries) {
  RowGroups g;
  std::vector<char> reduced(static_cast<std::size_t>(m.nc), 0);
  std::vector<int>& row_joint = g.row_joint;
  row_joint.assign(static_cast<std::size_t>(m.nc), -1);
  for (const GraphJoint& e : forest.edges) {
    const int row = m.joints[static_cast<std::size_t>(e.joint)].row;
    for (int r = 0; r < 6; ++r) {
      row_joint[static_cast<std::size_t>(row + r)] = e.joint;
      if (forest.IsChord(e)) reduced[static_cast<std::size_t>(row + r)] = 1;
    }
  }
  for (std::size_t jj = 0; jj < m.joints.size(); ++jj)
    if (m.joints[jj].drive_row >= 0) {
      reduced[static_cast<std::size_t>(m.joints[jj].drive_row)] = 1;
      row_joint[static_cast<std::size_t>(m.joints[jj].drive_row)] = static_cast<int>(jj);
    }
  std::vector<int> uf(static_cast<std::size_t>(m.nc));
  for (int r = 0; r < m.nc; ++r) uf[static_cast<std::size_t>(r)] = r;
  auto unite = [&](int a, int b) {
    a = Root(uf, a);
    b = Root(uf, b);
    if (a != b) uf[static_cast<std::size_t>(a)] = b;
  };
  for (const GraphJoint& e : forest.edges)  // a joint's rows are reported together
    for (int r = 1; r < 6; ++r)
      unite(m.joints[static_cast<std::size_t>(e.joint)].row,
            m.joints[static_cast<std::size_t>(e.joint)].row + r);
  {
    std::map<int, int> first_row_of_col;
    for (const Entry& en : entries) {
      const auto [it, inserted] = first_row_of_col.emplace(en.col, en.row);
      if (!inserted) unite(it->second, en.row);
    }
  }
  for (int r = 0; r < m.nc; ++r)
    if (reduced[static_cast<std::size_t>(r)]) g.rows[Root(uf, r)].push_back(r);
  for (const Entry& en : entries) g.entries[Root(uf, en.row)].push_back(&en);
  return g;
}

// The rank of each group (column-pivoting QR of its transpose): appends the redundant rows
// (the group's last pivots) to m.redundant_rows and sets z, the weights of one dependency per
// group on its rows. Returns the number of redundant rows, or -1 when the work passes the
// bound.
int RankGroups(Model& m, RowGroups& groups, Work* work, std::vector<double>* z) {
  int num_redundant = 0;
  for (const auto& [root, rows] : groups.rows) {
    std::map<int, int> col_index;
    for (const Entry* en : groups.entries[root]) col_index.emplace(en->col, 0);
    int ncols = 0;
    for (auto& [col, index] : col_index) index = ncols++;
    const int nrows = static_cast<int>(rows.size());
    work->spent += static_cast<double>(nrows) * nrows * std::max(ncols, 1) / 1000.0;
    if (work->spent > kMaxRedundancyWork) return -1;
    std::map<int, int> row_index;
    for (int i = 0; i < nrows; ++i) row_index[rows[static_cast<std::size_t>(i)]] = i;
    Eigen::MatrixXd Mt = Eigen::MatrixXd::Zero(std::max(ncols, 1), nrows);  // reduced rows^T
    for (const Entry* en : groups.entries[root])
      Mt(col_index[en->col], row_index[en->row]) += en->value;
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(Mt);
    qr.setThreshold(1e-10);
    const int rank = static_cast<int>(qr.rank());
    if (rank == nrows) continue;
    const auto& perm = qr.colsPermutation().indices();
    for (int c = rank; c < nrows; ++c)
      m.redundant_rows.push_back(rows[static_cast<std::size_t>(perm(c))]);
    num_redundant += nrows - rank;
    // Kernel of Mt: P [-R11^-1 R12; I]; their sum with fixed weights has the union of the
    // basis vectors' supports (cancellation would need the weights to be special).
    Eigen::VectorXd t(nrows - rank);
    for (int i = 0; i < nrows - rank; ++i) t(i) = 1.0 + 0.5 * std::sin(1.0 + i);
    Eigen::VectorXd y = Eigen::VectorXd::Zero(nrows);
    y.tail(nrows - rank) = t;
    if (rank > 0)
      y.head(rank) = -qr.matrixR()
                          .topLeftCorner(rank, rank)
                          .template triangularView<Eigen::Upper>()
                          .solve(qr.matrixR().topRightCorner(rank, nrows - rank) * t);
    for (int i = 0; i < nrows; ++i)
      (*z)[static_cast<std::size_t>(rows[static_cast<std::size_t>(perm(i))])] = y(i);
  }
  return num_redundant;
}

// The names of the joints a dependency y involves, quoted and comma-separated: z on the chord
// and drive rows, and w on the tree rows from the node balance of each tree joint's child,
// deepest first (w_e = -B_c^-T (sum of the other rows' B^T y on node c)).
std::string InvolvedJointNames(const Model& m, const JointForest& forest,
                               const std::vector<int>& row_joint, const std::vector<double>& z,
                               Work* work) {
  const int G = forest.ground;
  std::vector<double> joint_weight(m.joints.size(), 0.0);
  double zmax = 0.0;
  for (int r = 0; r < m.nc; ++r) {
    const double a = std::abs(z[static_cast<std::size_t>(r)]);
    zmax = std::max(zmax, a);
    double& w = joint_weight[static_cast<std::size_t>(row_joint[static_cast<std::size_t>(r)])];
    w = std::max(w, a);
  }
  // Node forces sum B^T y over the rows placed so far; tree joints on the chords' paths.
  std::map<int, Vec6> force;
  std::set<std::pair<int, int>> path;  // (-depth, child vertex) of tree joints walked
  for (const GraphJoint& chord : forest.edges) {
    if (!forest.IsChord(chord)) continue;
    const Joint& j = m.joints[static_cast<std::size_t>(chord.joint)];
    const Vec6 zc = Eigen::Map<const Vec6>(&z[static_cast<std::size_t>(j.row)]);
    if (zc.cwiseAbs().maxCoeff() == 0.0) continue;
    const Blocks cg = ReferenceGradient(m, chord.joint);
    if (chord.va != G)
      force.try_emplace(chord.va, Vec6::Zero()).first->second += cg.a.transpose() * zc;
    if (chord.vb != G)
      force.try_emplace(chord.vb, Vec6::Zero()).first->second += cg.b.transpose() * zc;
    WalkChord(m, forest, chord, cg, work, [&](int u, int, const Mat6&) {
      path.emplace(-forest.depth[static_cast<std::size_t>(u)], u);
    });
  }
  double wmax = zmax;
  for (const auto& [neg_depth, u] : path) {
    const int e = forest.parent_edge[static_cast<std::size_t>(u)];
    const GraphJoint& te = forest.edges[static_cast<std::size_t>(e)];
    const Blocks tg = ReferenceGradient(m, te.joint);
    const bool child_is_a = te.va == u;
    const Vec6 fu = force.count(u) ? force[u] : Vec6::Zero();
    const Vec6 w = -(child_is_a ? tg.a : tg.b).transpose().partialPivLu().solve(fu);
    const int p = forest.ParentOf(u);
    if (p != G)
      force.try_emplace(p, Vec6::Zero()).first->second +=
          (child_is_a ? tg.b : tg.a).transpose() * w;
    double& jw = joint_weight[static_cast<std::size_t>(te.joint)];
    jw = std::max(jw, w.cwiseAbs().maxCoeff());
    wmax = std::max(wmax, jw);
  }
  std::set<std::string> involved;
  for (std::size_t jj = 0; jj < m.joints.size(); ++jj)
    if (joint_weight[jj] > 1e-8 * wmax) involved.insert("'" + m.joints[jj].name + "'");
  std::string names;
  for (const std::string& n : involved) names += (names.empty() ? "" : ", ") + n;
  return names;
}

constexpr const char* kTooLargeWarning =
    "redundant-constraint check skipped (the closed loops are too many or too long)";

}  // namespace

void FindRedundantConstraints(Model& m) {
  m.redundant_rows.clear();
  if (m.nc == 0) return;
  Work work;
  const JointForest forest = BuildJointForest(m);
  const std::vector<Entry> entries = ReduceChordAndDriveRows(m, forest, &work);
  if (work.too_large) {
    m.warnings.push_back(kTooLargeWarning);
    return;
  }
  RowGroups groups = GroupReducedRows(m, forest, entries);
  std::vector<double> z(static_cast<std::size_t>(m.nc), 0.0);  // chord and drive weights
  const int num_redundant = RankGroups(m, groups, &work, &z);
  if (num_redundant < 0) {
    m.warnings.push_back(kTooLargeWarning);
    m.redundant_rows.clear();
    return;
  }
  if (num_redundant == 0) return;
  std::sort(m.redundant_rows.begin(), m.redundant_rows.end());
  const std::string names = InvolvedJointNames(m, forest, groups.row_joint, z, &work);
  m.warnings.push_back(std::to_string(num_redundant) +
                       " redundant constraint equation(s) among joints " + names +
                       "; their reaction components are not unique and are reported as zero "
                       "(the motion is unaffected)");
}

}  // namespace screwfem
