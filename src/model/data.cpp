#include "screwfem/model/data.h"

#include <algorithm>
#include <string>

#include "screwfem/model/memory.h"

namespace screwfem {

Data MakeData(const Model& model) {
  Data d;
  d.H.resize(model.nodes.size());
  for (std::size_t i = 0; i < model.nodes.size(); ++i) d.H[i] = model.nodes[i].reference;
  d.HJ.assign(model.joints.size(), SE3::Identity());
  d.q_joint = Eigen::VectorXd::Zero(model.nv - model.nv_nodes);
  d.v = Eigen::VectorXd::Zero(model.nv);
  d.vdot = Eigen::VectorXd::Zero(model.nv);
  d.lambda = Eigen::VectorXd::Zero(model.nc);
  d.w_ref.resize(model.elements.size());
  for (std::size_t e = 0; e < model.elements.size(); ++e)
    d.w_ref[e] = model.elements[e].d0.tail<3>();
  d.inputs.resize(static_cast<Eigen::Index>(model.inputs.size()));
  for (std::size_t i = 0; i < model.inputs.size(); ++i)
    d.inputs(static_cast<Eigen::Index>(i)) = model.inputs[i].default_value;
  d.tendon_slack.assign(model.tendons.size(), 0);
  if (KeepsContactAnchors(model))
    d.contact_anchors.assign(model.contact_pairs.size(), ContactAnchor{});
  // The swept check's reference and buffers (elements/crossing.h).
  if (!model.contact_segments.empty() || !model.contact_pairs.empty()) {
    d.crossing_points.assign(2 * (model.contact_segments.size() + model.contact_pairs.size()),
                             Vec3::Zero());
    d.crossing_lo.assign(model.contact_segments.size(), Vec3::Zero());
    d.crossing_hi.assign(model.contact_segments.size(), Vec3::Zero());
    d.crossing_order.assign(model.contact_segments.size(), 0);
  }
  d.residual = Eigen::VectorXd::Zero(model.num_unknowns());
  d.rhs = Eigen::VectorXd::Zero(model.num_unknowns());
  d.increment = Eigen::VectorXd::Zero(model.num_unknowns());
  d.node_tangent.assign(model.nodes.size(), Mat6::Identity());
  // The broad phase: each segment in at most 8 cells, twice as many buckets as entries. The
  // off-band coupling: room for 32 nodes at first (or every node of the shapes; none without
  // pairs of moving shapes).
  const std::size_t segments = model.contact_segments.size();
  int coupled_nodes = 0;
  if (segments > 0 && MayHaveShapePairs(model)) {
    ShapePairGrid& g = d.shape_pair_grid;
    // Chunks: consecutive elements of one rod spanning at most a diameter (and 16 elements).
    g.chunk_first.clear();
    for (std::size_t i = 0; i < segments; ++i) {
      const ContactSegment& s = model.contact_segments[i];
      if (!g.chunk_first.empty()) {
        const std::size_t first = static_cast<std::size_t>(g.chunk_first.back());
        const ContactSegment& f = model.contact_segments[first];
        if (s.side.rod && f.side.rod && s.entity == f.entity && i - first < 16 &&
            s.s1 - f.s0 <= 2.0 * s.side.radius * (1.0 + 1e-9))
          continue;
      }
      g.chunk_first.push_back(static_cast<int>(i));
    }
    g.chunk_first.push_back(static_cast<int>(segments));
    g.segment_lo.resize(segments);
    g.segment_hi.resize(segments);
    g.lo.resize(segments);
    g.hi.resize(segments);
    g.large.resize(segments);
    g.entry_chunk.resize(8 * segments);
    g.entry_cell.resize(8 * segments);
    std::size_t buckets = 1;
    while (buckets < 16 * segments) buckets *= 2;
    g.bucket_start.resize(buckets + 1);
    g.large_chunks.resize(segments);
    d.shape_pairs.resize(4 * segments + 64);
    if (KeepsContactAnchors(model)) {
      d.shape_pair_anchors.resize(d.shape_pairs.size());
      d.shape_pair_anchors_next.resize(d.shape_pairs.size());
    }
    std::vector<int> nodes;
    for (const ContactSegment& segment : model.contact_segments)
      for (int k : segment.side.node)
        if (k != kGround && model.nodes[static_cast<std::size_t>(k)].dof >= 0) nodes.push_back(k);
    std::sort(nodes.begin(), nodes.end());
    const int distinct = static_cast<int>(std::unique(nodes.begin(), nodes.end()) - nodes.begin());
    coupled_nodes = std::min(distinct, 32);
  }
  // The sparse LU holds the pairs' blocks in its pattern (SelectSparsePattern).
  if (model.sparse_solver) coupled_nodes = 0;
  if (model.sparse_solver) d.sparse_couplings.resize(6 * d.shape_pairs.size());
  d.coupling.Resize(model.num_unknowns(), 6, coupled_nodes);
  if (model.sparse_solver) {
    d.matrix.Resize(0, 0, 0);
    d.sparse.SetPivotTolerance(model.nc == 0 ? SparseLU::kDiagonalPivotTolerance
                                             : SparseLU::kConstrainedPivotTolerance);
    d.sparse.SetPattern(model.num_unknowns(), model.sparse_pattern);
  } else {
    d.matrix.Resize(model.num_unknowns(), model.bandwidth, model.bandwidth);
    if (static_cast<int>(model.pattern_last.size()) == model.num_unknowns())
      d.matrix.SetPattern(model.pattern_last, model.pattern_last);
  }
  return d;
}

void GrowShapePairPool(Data& data, std::size_t limit) {
  data.shape_pairs.resize(std::max<std::size_t>(64, std::min(limit, 2 * data.shape_pairs.size())));
  if (!data.sparse_couplings.empty()) data.sparse_couplings.resize(6 * data.shape_pairs.size());
  data.shape_pair_overflow = false;
  if (!data.shape_pair_anchors.empty()) {
    data.shape_pair_anchors.resize(data.shape_pairs.size());
    data.shape_pair_anchors_next.resize(data.shape_pairs.size());
  }
}

std::size_t ShapePairPoolLimit(const Model& model) {
  const double rest = TotalBytes(EstimateDataMemory(model));
  const double limit = static_cast<double>(ResolveMemoryLimit(model.memory_limit));
  const double room = std::max(0.0, (limit - rest) / (2.0 * sizeof(ShapePair)));
  // Never below the pool MakeData allocates.
  const double first = 4.0 * static_cast<double>(model.contact_segments.size()) + 64.0;
  return static_cast<std::size_t>(
      std::max(first, std::min(room, static_cast<double>(kMaxShapePairs))));
}

std::string ShapePairLimitMessage(const Model& model) {
  const std::size_t limit = ShapePairPoolLimit(model);
  return "the broad phase found more than " + std::to_string(limit) +
         " pairs of moving shapes near each other (the limit: at most " +
         std::to_string(kMaxShapePairs) + ", and " +
         FormatBytes(static_cast<double>(limit) * sizeof(ShapePair)) +
         " within the memory limit); a smaller contact onset, a larger self_skip or fewer, "
         "longer elements make fewer pairs";
}

}  // namespace screwfem
