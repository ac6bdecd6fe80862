// Error types. InputError: the user's model or scene is invalid (the message names what and
// where). SolverError: a numerical failure that the caller chose to turn into an exception.
#pragma once

#include <stdexcept>
#include <string>
#include <utility>

namespace screwfem {

// The entity of a model under construction that an InputError is about: its kind and its index
// in the builder's arrays (ModelBuilder, model.h), and optionally a named part of it: for rods
// "path[i]" (a point of AddRodAlongPath's polyline), "start_node" or "end_node" (a shared end
// node); for joints "node_a" or "node_b". A scene compiler maps it to the place in the file
// that defined the entity (io/scene_spec.h) without reading the message.
enum class EntityKind {
  kNone,
  kNode,
  kRod,
  kBody,
  kJoint,
  kPointLoad,
  kRodLoad,
  kTendon,        // part "eyelets[i]" for one eyelet
  kForceElement,  // part "a" or "b" for one end
  kActuator,
  kContactShape,  // Model::contact_shapes
  kObstacle,      // Model::obstacles
  kContactRod,    // Model::contact_rods
};
struct EntityRef {
  EntityKind kind = EntityKind::kNone;
  int index = -1;
  std::string part;  // empty: the whole entity
};

class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
  // `message` names the entity ("joint 'j': ..."); `detail` is the same message without that
  // label, for a caller that names the entity itself (empty: use what()).
  InputError(const std::string& message, EntityRef entity, std::string detail = {})
      : std::runtime_error(message), entity_(std::move(entity)), detail_(std::move(detail)) {}
  const EntityRef& entity() const { return entity_; }
  const std::string& detail() const { return detail_; }

 private:
  EntityRef entity_;
  std::string detail_;
};

// A message with up to three numbers printed by `format` (printf conventions, each number a
// double: "%g", "%.3g", ...), for the solvers' and the run loop's reports. Not for use inside a
// time step: it allocates.
std::string FormatNumbers(const char* format, double a, double b = 0.0, double c = 0.0);

class SolverError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Always-on internal invariant check (not for user input): aborts with a message.
[[noreturn]] void InternalCheckFailed(const char* condition, const char* file, int line);
#define SCREWFEM_CHECK(cond) \
  ((cond) ? static_cast<void>(0) : ::screwfem::InternalCheckFailed(#cond, __FILE__, __LINE__))

}  // namespace screwfem
