#include "screwfem/model/model.h"

#include <algorithm>
#include <map>
#include <utility>

namespace screwfem {

namespace {

template <typename T>
int FindByName(const std::vector<T>& items, const std::string& name) {
  for (std::size_t i = 0; i < items.size(); ++i)
    if (items[i].name == name) return static_cast<int>(i);
  return -1;
}

}  // namespace

void ContactEntityPairs::Finish() {
  std::sort(apart_.begin(), apart_.end());
  apart_.erase(std::unique(apart_.begin(), apart_.end()), apart_.end());
  // The pairs whose bits match, by classes of equal bits (a few), less those set apart.
  std::map<std::pair<unsigned, unsigned>, double> classes;
  for (std::size_t e = 0; e < contype_.size(); ++e) classes[{contype_[e], conaffinity_[e]}] += 1.0;
  pairs_ = 0.0;
  for (auto a = classes.begin(); a != classes.end(); ++a)
    for (auto b = a; b != classes.end(); ++b) {
      const auto [ta, ca] = a->first;
      const auto [tb, cb] = b->first;
      if (((ta & cb) | (tb & ca)) == 0u) continue;
      pairs_ += a == b ? 0.5 * a->second * (a->second - 1.0) : a->second * b->second;
    }
  for (unsigned long long k : apart_) {
    const std::size_t a = static_cast<std::size_t>(k >> 32),
                      b = static_cast<std::size_t>(k & 0xffffffffu);
    if (((contype_[a] & conaffinity_[b]) | (contype_[b] & conaffinity_[a])) != 0u) pairs_ -= 1.0;
  }
}

bool ContactEntityPairs::IsApart(int a, int b) const {
  return std::binary_search(apart_.begin(), apart_.end(), Key(a, b));
}

int Model::FindNode(const std::string& name) const { return FindByName(nodes, name); }
int Model::FindRod(const std::string& name) const { return FindByName(rods, name); }
int Model::FindBody(const std::string& name) const { return FindByName(bodies, name); }
int Model::FindJoint(const std::string& name) const { return FindByName(joints, name); }
int Model::FindTendon(const std::string& name) const { return FindByName(tendons, name); }
int Model::FindForceElement(const std::string& name) const {
  return FindByName(force_elements, name);
}
int Model::FindInput(const std::string& name) const { return FindByName(inputs, name); }
int Model::FindActuator(const std::string& name) const { return FindByName(actuators, name); }

}  // namespace screwfem
