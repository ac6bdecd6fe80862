// The initial state of a scene (docs/scene-format.md, "Initial state"): given joint coordinates,
// body velocities and joint rates, completed into a state that satisfies the constraints.
#pragma once

#include <string>

#include "screwfem/model/data.h"

namespace screwfem {

// Whether the model gives any initial coordinate or velocity (Node::has_initial_velocity,
// Joint::has_initial_coordinate, Joint::has_initial_rate).
bool HasInitialState(const Model& model);

// From data's configuration (the reference one after MakeData) at data.time:
//  1. sets the given joint coordinates and solves phi(q) = 0 for the others by Gauss-Newton
//     with the given ones held (minimum-norm corrections; the configuration closest to the
//     reference that the constraints allow, to first order);
//  2. sets the given body velocities and joint rates and solves B v + dphi/dt = 0 for the
//     other velocities (the minimum-norm correction, from zero).
// Nothing changes when the model gives nothing. Returns false with a message when the given
// values contradict the constraints (the residual does not vanish). Dense linear algebra:
// set-up only, never inside a step.
bool AssembleInitialState(const Model& model, Data& data, std::string* message = nullptr);

}  // namespace screwfem
