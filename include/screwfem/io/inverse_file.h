// Inverse statics from files: a targets file (YAML) for a scene, solved one target after the
// other (`screwfem inverse SCENE.yaml --targets TARGETS.yaml -o OUTDIR`; docs/inverse.md,
// "From the command line"; the file's keys: docs/scene-format.md, "Inverse targets file").
#pragma once

#include <string>
#include <vector>

#include "screwfem/io/scene.h"
#include "screwfem/solve/sensitivity.h"

namespace screwfem {

// A targets file read against a scene: the parameters the solver may change (with names for
// the table), their bounds, and per entry of `targets` the effector points with their targets.
struct InverseFile {
  std::vector<Parameter> parameters;
  std::vector<std::string> names;  // "input t1", "tendon a", "actuator c", "joint j"
  Eigen::VectorXd lower, upper;
  std::vector<std::string> points;                 // effector names (scene outputs.points)
  std::vector<std::vector<InverseTarget>> solves;  // one list (one target per point) per entry
  InverseStaticsOptions options;                   // the scene's statics, tolerance
};

// Parses the targets file's text (`source` names it in messages) against `scene`. Throws
// InputError "SOURCE:LINE:COL: FIELD: what is wrong" (unknown keys, items the scene does not
// have, bounds, points that are not on a node).
InverseFile ParseInverseFile(const std::string& text, const std::string& source,
                             const Scene& scene);
InverseFile LoadInverseFile(const std::string& path, const Scene& scene);

struct InverseRunResult {
  int reached = 0, unreachable = 0;
  std::string message;  // the unreachable targets, one line each
};

// Solves every entry in turn, each warm-started from the last solution, and writes
// OUTDIR/inverse.csv: per entry its index, whether it was reached, the distance [m], the
// parameters' values and the reached points (x, y, z of each effector) — for an unreachable
// entry the nearest equilibrium within the bounds. Creates OUTDIR; throws InputError when it
// cannot be written.
InverseRunResult RunInverseFile(const Scene& scene, const InverseFile& file,
                                const std::string& outdir);

}  // namespace screwfem
