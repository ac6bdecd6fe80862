// The registry of kinds: every element kind (element.h) and every constraint kind
// (constraint.h), listed once. The assembly, the energy, the constraint functions of the
// solvers and the solver ordering (build/) all loop over these lists, so a new kind is one
// line here (docs/architecture.md, "Recipe: add an element kind").
//
// The order is the order of assembly: it fixes the order in which contributions are summed,
// so changing it changes results at round-off.
#pragma once

#include <tuple>

#include "screwfem/elements/contact.h"
#include "screwfem/elements/force_span.h"
#include "screwfem/elements/joint.h"
#include "screwfem/elements/joint_constraint.h"
#include "screwfem/elements/loads.h"
#include "screwfem/elements/rigid_body.h"
#include "screwfem/elements/rod.h"
#include "screwfem/elements/shape_pair.h"
#include "screwfem/elements/tendon.h"
#include "screwfem/elements/tendon_length.h"

namespace screwfem {

using ElementKinds = std::tuple<RodElementKind, RigidBodyKind, PointLoadKind, RodLoadKind,
                                JointSpringKind, TendonSegmentKind, TendonSpanSegmentKind,
                                ForceElementKind, ForceElementSpanKind, ContactKind, ShapePairKind>;

using ConstraintKinds = std::tuple<JointConstraintKind, DriveConstraintKind, TendonLengthKind>;

// f.template operator()<Kind>() for each kind of a registry list, in order.
template <class Kinds, class F>
void ForEachKind(F&& f) {
  [&]<class... K>(std::tuple<K...>*) {
    (f.template operator()<K>(), ...);
  }(static_cast<Kinds*>(nullptr));
}

// The items of an element kind: from the Model, or from the Data for a kind whose items are
// found during the run (kItemsInData: the pairs of the contact broad phase).
template <class Kind, class F>
void ForEachItem(const Model& m, const Data& d, F&& f) {
  if constexpr (requires { Kind::kItemsInData; })
    Kind::ForEach(m, d, f);
  else
    Kind::ForEach(m, f);
}

// f(profile) for every profile that an item of a kind evaluates (the kinds' optional
// ForEachProfile): loads, drives, tendons, force elements, actuators. The steps of a run end on
// their breakpoints (solve/schedule.h, ProfileBreakpoints).
template <class F>
void ForEachKindProfile(const Model& model, F&& f) {
  const auto visit = [&]<class Kind>() {
    if constexpr (requires { Kind::ForEachProfile(model, f); }) Kind::ForEachProfile(model, f);
  };
  ForEachKind<ElementKinds>(visit);
  ForEachKind<ConstraintKinds>(visit);
}

// f(first_unknown, size) for every block of unknowns that constraint rows act on, kind by kind
// and item by item (a block may come more than once).
template <class F>
void ForEachConstraintColumn(const Model& model, F&& f) {
  ForEachKind<ConstraintKinds>([&]<class Kind>() {
    Kind::ForEach(model, [&](const typename Kind::Item& item) {
      if (Kind::RowCount(model, item) > 0) Kind::ForEachColumn(model, item, f);
    });
  });
}

}  // namespace screwfem
