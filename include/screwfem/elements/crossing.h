// Tunnelling (docs/numerics.md, "No tunnelling"): a swept check that finds a contact shape
// carried through another between the last accepted state and a candidate state, so that the
// solvers retry the step or load step smaller instead of accepting a state whose penalty
// contact never saw the pair (a rod swinging through a rod in one load step).
//
// The reference is the shapes' axis segments at the last accepted state (Data::crossing_points,
// kept by AcceptContactHistory; for a box its centre and rotation vector). A pair of moving
// shapes (two rod element capsules, a capsule or sphere of a body) crossed when the signed
// distance of their axis lines,
// (d_A x d_B) . (a_0 - b_0) with the end points moved linearly from the reference to the
// candidate, changes sign at a parameter where the two axis segments are nearer than half the
// sum of their radii, or when the axes are that near at the candidate and were not at the
// reference. A shape against an obstacle crossed when its axis point went behind a plane or
// into the axis of a capsule or sphere obstacle in the same sense. Two boxes crossed when, with
// one's points moved linearly in the other's frame, a corner went into the other's core (half
// its half sizes) or the centre into the box of half sizes (h_B + min h_A) / 2, from outside:
// a box carried through a thin one in a step.
// A box against a capsule, sphere or rod element is not checked. Candidate pairs come from a
// sweep-and-prune of the segments' swept boxes on one axis (Data's buffers, sized by MakeData):
// time O(n log n + k), no allocation.
#pragma once

#include <cstddef>
#include <string>

#include "screwfem/model/data.h"
#include "screwfem/model/model.h"

namespace screwfem {

// A crossing found: the two shapes by name (for messages).
struct Crossing {
  bool found = false;
  // Moving pair: Model::contact_segments indices a, b; obstacle pair: contact_pairs index in a,
  // b = -1.
  int a = -1, b = -1;
};

// Whether the model has shapes a crossing can concern (else the check is a no-op).
bool MayCross(const Model& model);

// The reference: the axis end points of every contact segment and obstacle pair at the state in
// data (called by AcceptContactHistory, so on every accepted step and at a run's start).
void SaveCrossingReference(const Model& model, Data& data);

// The swept check between the reference and the state in data; false (and *out untouched) when
// nothing crossed or there is no reference yet.
bool FindCrossing(const Model& model, Data& data, Crossing* out);

// "rod 'a' element 3 and rod 'b' element 0" into buf (no allocation), or as a string.
void FormatCrossing(const Model& model, const Crossing& crossing, char* buf, std::size_t size);
std::string DescribeCrossing(const Model& model, const Crossing& crossing);

// The one call of a time-step loop (solve/dynamics.cpp, error_control.cpp): a step that
// converged (iterations >= 0) but carried a shape through another counts as failed, so that it
// is retried smaller: returns -1 and sets *why (within its capacity, as a failed attempt's
// message), else returns `iterations`.
int CheckStepCrossing(const Model& model, Data& data, int iterations, std::string* why);

}  // namespace screwfem
