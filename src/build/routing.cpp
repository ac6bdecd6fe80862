#include "screwfem/build/routing.h"

#include <cmath>
#include <numbers>
#include <sstream>
#include <string>

namespace screwfem {

std::vector<BodyPoint> RouteAlongRod(const ModelBuilder& builder, const RodRoute& route) {
  const std::vector<double> arcs = builder.RodArcLengths(RodId(route.rod));
  const Rod& rod = builder.model().rods[static_cast<std::size_t>(route.rod)];
  const double length = arcs.back();
  const double to = route.to < 0.0 ? length : route.to;
  const double tolerance = 1e-8 * std::max(1.0, length);
  auto fail = [](const std::string& what) { throw InputError(what); };
  std::ostringstream s;
  s.precision(9);
  if (route.every < 1) fail("every: expected an integer of at least 1 (every k-th node)");
  if (!std::isfinite(route.from) || !std::isfinite(route.to) || !route.offset.allFinite() ||
      !std::isfinite(route.helix_radius) || !std::isfinite(route.helix_pitch) ||
      !std::isfinite(route.helix_phase))
    fail("the route's values must be finite");
  if (route.from < 0.0 || to > length + tolerance || !(to > route.from - tolerance)) {
    s << "from " << route.from << " m to " << to << " m is not a range on the rod (length "
      << length << " m)";
    fail(s.str());
  }
  if (route.helix_radius < 0.0) fail("helix radius: expected a non-negative number");
  if (route.helix_radius > 0.0 && route.helix_pitch == 0.0)
    fail("helix pitch: a helical route needs a non-zero pitch (arc length per turn)");
  // The nodes in [from, to].
  std::size_t first = 0;
  while (first < arcs.size() && arcs[first] < route.from - tolerance) ++first;
  std::size_t last = arcs.size();
  while (last > 0 && arcs[last - 1] > to + tolerance) --last;
  if (first >= last) {
    s << "no node lies from " << route.from << " m to " << to << " m";
    fail(s.str());
  }
  --last;  // the last node in the range
  std::vector<BodyPoint> eyelets;
  auto add = [&](std::size_t i) {
    Vec3 offset = route.offset;
    if (route.helix_radius > 0.0) {
      const double a =
          route.helix_phase + 2.0 * std::numbers::pi * (arcs[i] - route.from) / route.helix_pitch;
      offset += route.helix_radius * Vec3(0.0, std::cos(a), std::sin(a));
    }
    eyelets.push_back(BodyPoint{rod.nodes[i], offset});
  };
  const auto step = static_cast<std::size_t>(route.every);
  for (std::size_t i = first; i <= last; i += step) add(i);
  if ((last - first) % step != 0) add(last);
  return eyelets;
}

}  // namespace screwfem
