// Internal to screwfem::build: the steps of ModelBuilder::Build() (build/model_builder.cpp),
// grouped by the source that defines them, and the helpers those sources share. Build() runs
// the steps in the order of its body; each works on the copy of the builder's model, fills what
// its source is about and throws InputError (with the entity) for what it finds invalid. What
// each step checks and computes is said above its definition.
#pragma once

#include <string>
#include <vector>

#include "screwfem/model/errors.h"
#include "screwfem/model/model.h"
#include "screwfem/model/profile.h"

namespace screwfem::build_steps {

// Shared helpers (build/validate.cpp).
// "ground", "node 3" or "node 'name'": how errors name a node.
std::string NodeLabel(const Model& m, int node);
// Profile::Validate against the model's inputs, rethrown with the profile's owner as entity.
void ValidateProfile(const Model& m, const Profile& profile, const std::string& label,
                     const EntityRef& entity);

// Validation of nodes, rods, bodies and joints (build/validate.cpp). `used` marks the nodes
// that a rod, a body or a joint is attached to; CheckConnected reads it.
void ValidateNodes(const Model& m);
// The rod meshes conformed to the features on them (build/conform_mesh.cpp; Model::conform_mesh):
// runs before BuildRodElements, on the rods' node lists.
void ConformRodMeshes(Model& m);
void BuildRodElements(Model& m, std::vector<char>& used);
void ValidateBodies(const Model& m, std::vector<char>& used);
void ValidateJoints(const Model& m, std::vector<char>& used);
void CheckConnected(const Model& m, const std::vector<char>& used);
void CheckJointFramesCoincide(const Model& m);

// Loads, tendons, force elements and actuators placed on the rods (build/place_items.cpp).
void PlaceLoads(Model& m);
void BuildTendons(Model& m);
void BuildForceElements(Model& m);
void BuildActuators(Model& m);

// Contact pairs, segments and the law's defaults (build/contact_build.cpp).
void BuildContacts(Model& m);

// Length scale, layout of the unknowns and the solver ordering (build/ordering.cpp).
void SetLengthScale(Model& m);
void LayOutUnknowns(Model& m);
void OrderUnknowns(Model& m);

}  // namespace screwfem::build_steps
