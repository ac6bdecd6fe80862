#include "screwfem/solve/rest.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "screwfem/model/errors.h"

namespace screwfem {

void ValidateRestCriterion(const RestCriterion& c, const std::string& owner) {
  const auto require = [&](bool ok, const char* field, const char* what) {
    if (!ok) throw InputError(owner + "." + field + ": " + what);
  };
  require(std::isfinite(c.speed) && c.speed > 0.0, "speed", "must be a speed > 0 [m/s]");
  require(std::isfinite(c.angular_speed) && c.angular_speed > 0.0, "angular_speed",
          "must be an angular speed > 0 [rad/s]");
  require(std::isfinite(c.hold) && c.hold >= 0.0, "hold", "must be a duration >= 0 [s]");
}

bool RestWatch::Update(const Model& model, const Data& data) {
  const NodeSpeeds s = LargestNodeSpeeds(model, data);
  if (!(s.linear < criterion_.speed && s.angular < criterion_.angular_speed)) {
    since_ = std::numeric_limits<double>::quiet_NaN();
    return false;
  }
  if (std::isnan(since_)) since_ = data.time;
  return data.time >= earliest_ && data.time - since_ >= criterion_.hold * (1.0 - 1e-12);
}

}  // namespace screwfem
