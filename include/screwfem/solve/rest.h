// Settling: when a simulation has come to rest (analysis.stop_at_rest; docs/numerics.md,
// "Settling and rest"). A pile, a gripper closing on an object or a rod dropped on a plane ends
// at rest long before a generous end_time: a run can end there.
#pragma once

#include <limits>
#include <string>

#include "screwfem/assemble/outputs.h"  // LargestNodeSpeeds
#include "screwfem/model/data.h"

namespace screwfem {

// The scene at rest: every free node's translational speed below `speed` and its angular speed
// below `angular_speed`, continuously for `hold` seconds of simulated time (one slow instant at
// the top of a bounce is not rest).
struct RestCriterion {
  bool enabled = false;         // analysis.stop_at_rest
  double speed = 1e-3;          // [m/s] > 0
  double angular_speed = 1e-2;  // [rad/s] > 0
  double hold = 0.1;            // [s] >= 0
};

// Throws InputError "<owner>.<field>: ..." unless the values are finite and in range.
void ValidateRestCriterion(const RestCriterion& c, const std::string& owner);

// Watches the accepted steps of a run for rest. Update after each accepted step: true once the
// criterion has held for `hold` from the first state below it, and not before `earliest` (the
// last time at which an input changes: the run's profile breakpoints and input-table rows; a
// scene at rest before a drive starts is waiting, not settled). Allocates nothing.
class RestWatch {
 public:
  RestWatch() = default;
  RestWatch(const RestCriterion& criterion, double earliest)
      : criterion_(criterion), earliest_(earliest) {}
  bool Update(const Model& model, const Data& data);
  // When the scene came to rest (the start of the held interval), NaN while it is moving.
  double since() const { return since_; }
  const RestCriterion& criterion() const { return criterion_; }

 private:
  RestCriterion criterion_;
  double earliest_ = -std::numeric_limits<double>::infinity();
  double since_ = std::numeric_limits<double>::quiet_NaN();
};

}  // namespace screwfem
