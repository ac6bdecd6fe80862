#include "screwfem/model/model.h"

namespace screwfem {

namespace {

template <typename T>
int FindByName(const std::vector<T>& items, const std::string& name) {
  for (std::size_t i = 0; i < items.size(); ++i)
    if (items[i].name == name) return static_cast<int>(i);
  return -1;
}

}  // namespace

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
