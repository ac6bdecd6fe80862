// Routing helpers: a tendon's eyelets on the nodes of a rod by rule (docs/scene-format.md,
// "Routing helpers"), instead of one eyelet per line. The scene key `route` of a tendon's
// eyelet list, ModelBuilder users in C++ and Python (screwfem.RodRoute, route_along_rod) all
// expand through RouteAlongRod, so the three give the same eyelets.
#pragma once

#include <vector>

#include "screwfem/build/model_builder.h"
#include "screwfem/model/model.h"

namespace screwfem {

// Eyelets on the nodes of one rod, from arc length `from` to `to`: the first node at or after
// `from`, every `every`-th node after it, and the last node at or before `to` (always). Each
// sits at `offset` in its section frame, plus, on a helical route, a turning offset
// radius (0, cos a, sin a) with a = phase + 2 pi (s - from) / pitch, s the node's arc length
// (a helix of that radius and pitch around the rod's axis; a negative pitch turns the other
// way).
struct RodRoute {
  int rod = -1;                // the rod (a RodId's value; -1 in a scene spec: its body)
  int every = 1;               // every k-th node (k >= 1)
  double from = 0.0;           // [m] reference arc length where the route starts
  double to = -1.0;            // [m] where it ends; negative: the rod's end
  Vec3 offset = Vec3::Zero();  // [m] section-frame components (axial, 2, 3)
  double helix_radius = 0.0;   // [m]; 0: no helix
  double helix_pitch = 0.0;    // [m of arc length per turn]; needed when helix_radius > 0
  double helix_phase = 0.0;    // [rad] angle of the helical offset at `from`, from section axis 2
};

// The eyelets of a route, in order along the rod (node body points: BodyPoint{node, offset}).
// Throws InputError (plain message, no entity) for an invalid rod, every < 1, a range that is
// off the rod or empty, a range holding no node, non-finite values, or a helix without pitch.
std::vector<BodyPoint> RouteAlongRod(const ModelBuilder& builder, const RodRoute& route);

}  // namespace screwfem
