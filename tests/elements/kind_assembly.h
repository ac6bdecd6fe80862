// Test helpers shared by the element tests of kinds on rod sections (tendon_eyelet_test.cpp,
// force_span_test.cpp): one kind's items assembled into node-indexed rows (6 per node, T =
// identity), and central differences through the retraction H <- H exp(+-eps e_j) of every
// node.
#pragma once

#include <gtest/gtest.h>

#include <random>

#include "screwfem/elements/element.h"

namespace screwfem::kind_assembly {

// The node rows of one kind's items and their stiffness (K) and damping (C) blocks, each
// optional, at the state of d (velocities from d.v when o.dynamics).
template <class Kind>
void AssembleKind(const Model& m, const Data& d, const KernelOptions& o, Eigen::VectorXd* r,
                  Eigen::MatrixXd* K, Eigen::MatrixXd* C = nullptr) {
  constexpr int N = Kind::kNodes;
  const int n = static_cast<int>(m.nodes.size());
  r->setZero(6 * n);
  if (K) K->setZero(6 * n, 6 * n);
  if (C) C->setZero(6 * n, 6 * n);
  Kind::ForEach(m, [&](const typename Kind::Item& item, const int(&nodes)[N]) {
    NodeMotion<N> x;
    const Mat6 I = Mat6::Identity();
    for (int i = 0; i < N; ++i) {
      x.H[i] = &NodeFrame(d, nodes[i]);
      x.T[i] = &I;
    }
    GatherNodeMotion<N>(m, d, nodes, &x.eta, &x.eta_dot);
    ElementTerms<N> t;
    ASSERT_TRUE(Kind::Calc(m, d, item, x, o, &t));
    if (!t.active) return;
    for (int a = 0; a < N; ++a) {
      if (nodes[a] == kGround) continue;
      r->template segment<6>(6 * nodes[a]) += t.residual.template segment<6>(6 * a);
      for (int b = 0; b < N; ++b) {
        if (nodes[b] == kGround) continue;
        if (K) {
          ASSERT_TRUE(t.has_stiffness || t.combined);
          K->block<6, 6>(6 * nodes[a], 6 * nodes[b]) +=
              (t.combined ? t.matrix : t.stiffness).template block<6, 6>(6 * a, 6 * b);
        }
        if (C && t.has_damping)
          C->block<6, 6>(6 * nodes[a], 6 * nodes[b]) +=
              t.damping.template block<6, 6>(6 * a, 6 * b);
      }
    }
  });
}

// d f / d(dh of every node) by central differences of f(Data) through the retraction.
template <class F>
Eigen::MatrixXd FiniteDifference(const Model& model, const Data& data, F&& f, double eps) {
  const int n = static_cast<int>(model.nodes.size());
  Eigen::MatrixXd J;
  for (int j = 0; j < 6 * n; ++j) {
    Data p = data, m = data;
    const Vec6 dh = eps * Vec6::Unit(j % 6);
    p.H[static_cast<std::size_t>(j / 6)] = p.H[static_cast<std::size_t>(j / 6)] * ExpSE3(dh);
    m.H[static_cast<std::size_t>(j / 6)] = m.H[static_cast<std::size_t>(j / 6)] * ExpSE3(-dh);
    const Eigen::VectorXd col = (f(p) - f(m)) / (2 * eps);
    if (J.size() == 0) J.setZero(col.size(), 6 * n);
    J.col(j) = col;
  }
  return J;
}

// Moves every node frame by exp of a random increment, up to `move` [m] and `turn` [rad] per
// component.
inline void PerturbFrames(std::mt19937& rng, double move, double turn, Data* d) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (SE3& H : d->H) {
    Vec6 dh;
    for (int k = 0; k < 6; ++k) dh(k) = (k < 3 ? move : turn) * u(rng);
    H = H * ExpSE3(dh);
  }
}

}  // namespace screwfem::kind_assembly
