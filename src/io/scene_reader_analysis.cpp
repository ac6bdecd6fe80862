// The scene reader (scene_reader_impl.h): the analysis (times, step control, solver options,
// statics) and the outputs.
#include <Eigen/Cholesky>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <sstream>
#include <unordered_map>

#include "scene_reader_impl.h"
#include "screwfem/io/scene_spec.h"
#include "screwfem/model/errors.h"
#include "screwfem/solve/schedule.h"

namespace screwfem::scene_reading {

void SceneReader::ReadAnalysis(const Node* node) {
  AnalysisSettings* a = &spec_.analysis;
  if (node == nullptr || node->IsNull()) return;
  const std::string path = "analysis";
  r_.CheckKeys(*node, path,
               {"type",
                "start_time",
                "end_time",
                "step",
                "rho_inf",
                "tolerances",
                "max_iterations",
                "max_halvings",
                "align_steps",
                "static_preload",
                "load_steps",
                "rod_inertia",
                "linear_solver",
                "newton",
                "predictor",
                "convergence",
                "restart_at_breakpoints",
                "perturbed_start",
                "constraints",
                "tolerance",
                "min_step",
                "max_step",
                "initial_step",
                "statics",
                "threads",
                "line_search",
                "stop_at_rest"});
  if (const Node* t = node->Find("type")) a->kind = r_.Enum<AnalysisKind>(*t, Join(path, "type"));
  ReadTimes(*node, path);
  ReadSolverOptions(*node, path);
  if (const Node* t = node->Find("statics")) ReadStatics(*t, Join(path, "statics"));
  if (const Node* t = node->Find("align_steps"))
    a->align_steps = r_.Bool(*t, Join(path, "align_steps"));
  if (const Node* t = node->Find("restart_at_breakpoints"))
    a->dynamic.restart_at_breakpoints = r_.Bool(*t, Join(path, "restart_at_breakpoints"));
  if (const Node* t = node->Find("perturbed_start"))
    a->dynamic.perturbed_start = r_.Bool(*t, Join(path, "perturbed_start"));
  if (const Node* t = node->Find("constraints"))
    a->dynamic.constraints = r_.Enum<ConstraintFormulation>(*t, Join(path, "constraints"));
  if (const Node* t = node->Find("static_preload"))
    a->static_preload = r_.Bool(*t, Join(path, "static_preload"));
  if (const Node* t = node->Find("rod_inertia"))
    spec_.rod_inertia = r_.Enum<RodInertia>(*t, Join(path, "rod_inertia"));
  if (const Node* t = node->Find("linear_solver"))
    spec_.linear_solver = r_.Enum<LinearSolver>(*t, Join(path, "linear_solver"));
  if (const Node* t = node->Find("threads")) ReadThreads(*t, Join(path, "threads"));
  if (const Node* t = node->Find("stop_at_rest")) ReadStopAtRest(*t, Join(path, "stop_at_rest"));
  // analysis.statics.time follows from the kind; the compiler sets it (SceneSpec::analysis).
}

// analysis.stop_at_rest: a bool (the default criterion) or a map of speed, angular_speed and
// hold; dynamic analyses only.
void SceneReader::ReadStopAtRest(const Node& node, const std::string& path) {
  RestCriterion* c = &spec_.analysis.stop_at_rest;
  if (node.IsMap()) {
    r_.CheckKeys(node, path, {"speed", "angular_speed", "hold"});
    c->enabled = true;
    if (const Node* v = node.Find("speed")) c->speed = r_.PositiveNumber(*v, Join(path, "speed"));
    if (const Node* v = node.Find("angular_speed"))
      c->angular_speed = r_.PositiveNumber(*v, Join(path, "angular_speed"));
    if (const Node* v = node.Find("hold")) c->hold = r_.NonNegativeNumber(*v, Join(path, "hold"));
  } else {
    c->enabled = r_.Bool(node, path);
  }
  if (c->enabled && spec_.analysis.kind == AnalysisKind::kStatic)
    r_.Fail(node.location, path,
            "applies to dynamic analyses only (a static analysis has no motion to come to rest)");
}

// analysis.threads: 'auto' or an integer from 1 to kMaxAssemblyThreads.
void SceneReader::ReadThreads(const Node& node, const std::string& path) {
  AnalysisSettings* a = &spec_.analysis;
  const std::string expected =
      "expected 'auto' or an integer from 1 to " + std::to_string(kMaxAssemblyThreads);
  if (!node.IsScalar()) r_.Fail(node.location, path, expected);
  if (!node.quoted && node.scalar == "auto") {
    a->threads = kAutoThreads;
    return;
  }
  char* end = nullptr;
  const double v = std::strtod(node.scalar.c_str(), &end);
  if (node.quoted || node.scalar.empty() || *end != '\0' || !(v >= 1.0) ||
      !(v <= kMaxAssemblyThreads) || v != std::floor(v))
    r_.Fail(node.location, path, expected + ", got '" + node.scalar + "'");
  a->threads = static_cast<int>(v);
}

// start_time, end_time, step: a time grid that a dynamic analysis can step through.
void SceneReader::ReadTimes(const Node& node, const std::string& path) {
  AnalysisSettings* a = &spec_.analysis;
  auto find = [&](const char* key) { return node.Find(key); };
  if (const Node* t = find("start_time")) a->start_time = r_.Number(*t, Join(path, "start_time"));
  if (const Node* t = find("end_time")) {
    a->end_time = r_.Number(*t, Join(path, "end_time"));
    if (!(a->end_time > a->start_time))
      r_.Fail(t->location, Join(path, "end_time"), "expected end_time > start_time");
  } else if (!(a->end_time > a->start_time)) {
    r_.Fail(node.location, path, "start_time must be before end_time (default 1 s)");
  }
  const Node* step = find("step");
  if (step != nullptr && step->IsScalar() && !step->quoted && step->scalar == "auto")
    ReadStepControl(node, path);
  else if (step != nullptr)
    a->step = r_.PositiveNumber(*step, Join(path, "step"));
  if (!a->adaptive_steps)
    for (const char* key : {"tolerance", "min_step", "max_step", "initial_step"})
      if (const Node* t = find(key))
        r_.Fail(t->location, Join(path, key),
                "applies only to 'step: auto' (error-controlled steps)");
  if (a->kind != AnalysisKind::kDynamic) return;
  if ((a->end_time - a->start_time) / a->step > kMaxSteps)
    r_.Fail(find("step") != nullptr ? find("step")->location : node.location, Join(path, "step"),
            "more than 1e9 time steps from start_time to end_time");
  // Times so large that their doubles are coarser than the step (schedule.h).
  const std::string problem = TimeGridProblem(a->start_time, a->end_time, a->step);
  if (!problem.empty()) {
    const char* key = std::abs(a->start_time) > std::abs(a->end_time) ? "start_time" : "end_time";
    const Node* at = find(key) != nullptr      ? find(key)
                     : find("step") != nullptr ? find("step")
                                               : &node;
    r_.Fail(at->location, Join(path, key), problem);
  }
}

// step: auto: tolerance (required; a number for both, or {absolute, relative}), min_step,
// max_step, initial_step (DynamicOptions). analysis.step becomes the first step.
void SceneReader::ReadStepControl(const Node& node, const std::string& path) {
  AnalysisSettings* a = &spec_.analysis;
  DynamicOptions& d = a->dynamic;
  a->adaptive_steps = true;
  const Node* tol = node.Find("tolerance");
  if (tol == nullptr)
    r_.Fail(
        node.Find("step")->location, Join(path, "step"),
        "'step: auto' requires analysis.tolerance (a number, or {absolute: .., relative: ..}: "
        "the local error per step, translations relative to the model's size, rotations in rad)");
  const std::string tp = Join(path, "tolerance");
  if (tol->IsMap()) {
    r_.CheckKeys(*tol, tp, {"absolute", "relative"});
    if (const Node* v = tol->Find("absolute"))
      d.absolute_tolerance = r_.PositiveNumber(*v, Join(tp, "absolute"));
    if (const Node* v = tol->Find("relative"))
      d.relative_tolerance = r_.NonNegativeNumber(*v, Join(tp, "relative"));
  } else {
    d.absolute_tolerance = d.relative_tolerance = r_.PositiveNumber(*tol, tp);
  }
  const double span = a->end_time - a->start_time;
  if (const Node* t = node.Find("min_step"))
    d.min_step = r_.PositiveNumber(*t, Join(path, "min_step"));
  if (const Node* t = node.Find("max_step")) {
    d.max_step = r_.PositiveNumber(*t, Join(path, "max_step"));
    if (!(d.max_step >= d.min_step))
      r_.Fail(t->location, Join(path, "max_step"), "expected max_step >= min_step");
  }
  a->step = std::clamp(1e-3 * span, d.min_step, d.max_step);
  if (const Node* t = node.Find("initial_step")) {
    a->step = r_.PositiveNumber(*t, Join(path, "initial_step"));
    if (a->step < d.min_step || a->step > d.max_step)
      r_.Fail(t->location, Join(path, "initial_step"), "expected a step in [min_step, max_step]");
  }
  d.initial_step = a->step;
}

// The Newton iteration's options, shared by dynamics and statics where both have them.
void SceneReader::ReadSolverOptions(const Node& node, const std::string& path) {
  AnalysisSettings* a = &spec_.analysis;
  if (const Node* t = node.Find("rho_inf")) {
    if (t->IsScalar() && !t->quoted && t->scalar == "auto") {
      a->dynamic.rho_inf = kAutoRhoInf;
    } else {
      a->dynamic.rho_inf = r_.Number(*t, Join(path, "rho_inf"));
      if (!(a->dynamic.rho_inf >= 0.0 && a->dynamic.rho_inf <= 1.0))
        r_.Fail(t->location, Join(path, "rho_inf"),
                "expected a spectral radius in [0, 1] or 'auto'");
    }
  }
  if (const Node* t = node.Find("line_search"))
    a->dynamic.line_search = r_.Bool(*t, Join(path, "line_search"));
  if (const Node* t = node.Find("tolerances")) {
    const std::string tp = Join(path, "tolerances");
    r_.CheckKeys(*t, tp, {"increment", "constraint", "residual"});
    if (const Node* v = t->Find("increment"))
      a->dynamic.increment_tolerance = a->statics.increment_tolerance =
          r_.PositiveNumber(*v, Join(tp, "increment"));
    if (const Node* v = t->Find("constraint"))
      a->dynamic.constraint_tolerance = a->statics.constraint_tolerance =
          r_.PositiveNumber(*v, Join(tp, "constraint"));
    if (const Node* v = t->Find("residual"))
      a->dynamic.residual_tolerance = a->statics.residual_tolerance =
          r_.PositiveNumber(*v, Join(tp, "residual"));
  }
  if (const Node* t = node.Find("max_iterations"))
    a->dynamic.max_iterations = a->statics.max_iterations =
        r_.Integer(*t, Join(path, "max_iterations"), 1, kMaxNewtonIterations);
  if (const Node* t = node.Find("max_halvings"))
    a->dynamic.max_halvings = a->statics.max_halvings =
        r_.Integer(*t, Join(path, "max_halvings"), 0, kMaxHalvings);
  if (const Node* t = node.Find("newton"))
    a->dynamic.newton_matrix = r_.Enum<NewtonMatrix>(*t, Join(path, "newton"));
  if (const Node* t = node.Find("predictor"))
    a->dynamic.predictor = r_.Enum<Predictor>(*t, Join(path, "predictor"));
  if (const Node* t = node.Find("convergence"))
    a->dynamic.convergence = r_.Enum<ConvergenceTest>(*t, Join(path, "convergence"));
  if (const Node* t = node.Find("load_steps"))
    a->statics.load_steps = r_.Integer(*t, Join(path, "load_steps"), 1, kMaxLoadSteps);
}

// analysis.statics: how a static solution follows its path (statics.h, StaticOptions).
void SceneReader::ReadStatics(const Node& node, const std::string& path) {
  StaticOptions* o = &spec_.analysis.statics;
  r_.CheckKeys(node, path,
               {"method", "end_load_factor", "max_steps", "arc_length", "arc_length_min",
                "arc_length_max", "desired_iterations", "psi", "rotation_weight", "exact_tangent"});
  const auto field = [&](const char* key) { return Join(path, key); };
  if (const Node* t = node.Find("method")) o->method = r_.Enum<StaticMethod>(*t, field("method"));
  if (const Node* t = node.Find("end_load_factor"))
    o->end_load_factor = r_.Number(*t, field("end_load_factor"));
  if (const Node* t = node.Find("max_steps"))
    o->max_steps = r_.Integer(*t, field("max_steps"), 1, kMaxStaticSteps);
  if (const Node* t = node.Find("arc_length"))
    o->arc_length = r_.PositiveNumber(*t, field("arc_length"));
  if (const Node* t = node.Find("arc_length_min"))
    o->arc_length_min = r_.PositiveNumber(*t, field("arc_length_min"));
  if (const Node* t = node.Find("arc_length_max")) {
    o->arc_length_max = r_.PositiveNumber(*t, field("arc_length_max"));
    if (o->arc_length_min > o->arc_length_max)
      r_.Fail(t->location, field("arc_length_max"), "expected arc_length_max >= arc_length_min");
  }
  if (const Node* t = node.Find("desired_iterations"))
    o->desired_iterations = r_.Integer(*t, field("desired_iterations"), 1, kMaxNewtonIterations);
  if (const Node* t = node.Find("psi")) o->psi = r_.NonNegativeNumber(*t, field("psi"));
  if (const Node* t = node.Find("rotation_weight"))
    o->rotation_weight = r_.NonNegativeNumber(*t, field("rotation_weight"));
  if (const Node* t = node.Find("exact_tangent"))
    o->constraint_force_tangent = r_.Bool(*t, field("exact_tangent"));
}

// The defaults (every joint with coordinates, the intervals of about kDefaultOutputRows rows
// and kDefaultVtkFrames frames) are OutputsSpec's, resolved by the compiler.
void SceneReader::ReadOutputs(const Node* node) {
  OutputsSpec* out = &spec_.outputs;
  if (node == nullptr || node->IsNull()) return;
  const std::string path = "outputs";
  r_.CheckKeys(*node, path,
               {"points", "joints", "interval", "vtk", "vtk_format", "vtk_interval", "rod_fields",
                "max_rows", "reactions", "energy"});
  if (const Node* pts = node->Find("points")) {
    const std::string pp = Join(path, "points");
    r_.CheckNames(*pts, pp, "output point");
    for (const auto& [entry, value] : pts->entries) {
      const std::string p = Join(pp, entry.key);
      src_.output_points.push_back({Field(entry.key_location, p), {}});
      out->points.emplace_back();
      out->points.back().name = entry.key;
      ReadOutputPoint(value, p, out->points.back(), src_.output_points.back());
    }
  }
  if (const Node* jn = node->Find("joints")) ReadOutputJoints(*jn, Join(path, "joints"));
  if (const Node* v = node->Find("interval"))
    out->interval = r_.NonNegativeNumber(*v, Join(path, "interval"));
  if (const Node* v = node->Find("vtk")) out->vtk = r_.Bool(*v, Join(path, "vtk"));
  if (const Node* v = node->Find("vtk_format"))
    out->vtk_format = r_.Enum<VtkFormat>(*v, Join(path, "vtk_format"));
  if (const Node* v = node->Find("vtk_interval"))
    out->vtk_interval = r_.NonNegativeNumber(*v, Join(path, "vtk_interval"));
  if (const Node* v = node->Find("rod_fields")) ReadRodFields(*v, Join(path, "rod_fields"));
  if (const Node* v = node->Find("max_rows"))
    out->max_rows = r_.Integer(*v, Join(path, "max_rows"), 1, static_cast<int>(kMaxMaxRows));
  if (const Node* v = node->Find("reactions"))
    out->reactions = r_.Bool(*v, Join(path, "reactions"));
  if (const Node* v = node->Find("energy")) out->energy = r_.Bool(*v, Join(path, "energy"));
}

// true (at the rows of points.csv), false, or the interval between rows [s] (>= 0).
void SceneReader::ReadRodFields(const Node& v, const std::string& path) {
  OutputsSpec* out = &spec_.outputs;
  std::string word = v.IsScalar() ? v.scalar : std::string();
  for (char& c : word) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (word == "true" || word == "false") {
    out->rod_fields = r_.Bool(v, path);
    out->rod_fields_interval = -1.0;
    return;
  }
  double interval = 0.0;
  std::string error;
  if (!v.IsScalar() || !scene_yaml::EvaluateExpression(v.scalar, &interval, &error) ||
      !std::isfinite(interval) || interval < 0.0)
    r_.Fail(v.location, path,
            "expected true, false or the interval between rows in s (a number >= 0), got " +
                (v.IsScalar() ? "'" + v.scalar + "'" : scene_yaml::Describe(v)));
  out->rod_fields = true;
  out->rod_fields_interval = interval;
}

void SceneReader::ReadOutputPoint(const Node& value, const std::string& p, OutputPointSpec& op,
                                  EntitySource& source) {
  r_.CheckKeys(value, p, {"body", "at", "rod", "s"});
  const Node* bn = value.Find("body");
  const Node* rn = value.Find("rod");
  if (bn != nullptr && rn != nullptr)
    r_.Fail(rn->location, Join(p, "rod"), "give either {body, at} or {rod, s}, not both");
  if (bn == nullptr && rn == nullptr)
    r_.Fail(value.location, p, "missing key 'body' (with 'at') or 'rod' (with 's')");
  if (bn != nullptr) {
    NotUsedBy(value, p, {"s"}, "body points (use 'rod' and 's' for a point along a rod)");
    op.body = Body(*bn, Join(p, "body"));
    const Node& an = r_.Require(value, p, "at");
    op.at = Point(an, Join(p, "at"));
    source.parts.emplace_back("at", Field(an.location, Join(p, "at")));
    return;
  }
  NotUsedBy(value, p, {"at"}, "rod points (use 'body' and 'at' for a node point)");
  op.body = Body(*rn, Join(p, "rod"));
  const BodySpec& body = spec_.bodies[static_cast<std::size_t>(op.body)];
  if (body.rigid)
    r_.Fail(rn->location, Join(p, "rod"),
            "'" + body.name + "' is a rigid body; use {body: " + body.name + ", at: POINT}");
  const Node& sn = r_.Require(value, p, "s");
  op.along_rod = true;
  op.arc_length = r_.NonNegativeNumber(sn, Join(p, "s"));
  source.parts.emplace_back("s", Field(sn.location, Join(p, "s")));
}

// 'all', 'none' or a list of joint names (with coordinates, each once).
void SceneReader::ReadOutputJoints(const Node& jn, const std::string& jp) {
  std::vector<int>& out = spec_.outputs.joints;
  out.clear();
  if (jn.IsScalar() && (jn.scalar == "all" || jn.scalar == "none")) {
    spec_.outputs.all_joints = jn.scalar == "all";
    return;
  }
  if (!jn.IsSequence())
    r_.Fail(jn.location, jp,
            "expected 'all', 'none' or a list of joint names, got " + scene_yaml::Describe(jn));
  spec_.outputs.all_joints = false;
  std::vector<std::string> names;
  for (const JointEntrySpec& j : spec_.joints) names.push_back(j.joint.name);
  for (std::size_t i = 0; i < jn.items.size(); ++i) {
    const Node& item = jn.items[i];
    const std::string ip = Index(jp, i);
    const std::string name = r_.Text(item, ip);
    const auto found = std::find(names.begin(), names.end(), name);
    if (found == names.end())
      r_.Fail(item.location, ip,
              "undefined joint '" + name + "'" + scene_yaml::DidYouMean(name, names));
    const int index = static_cast<int>(found - names.begin());
    if (GetJointTypeInfo(spec_.joints[static_cast<std::size_t>(index)].joint.type).dof == 0)
      r_.Fail(item.location, ip, "joint '" + name + "' is fixed: it has no coordinates to record");
    if (std::find(out.begin(), out.end(), index) != out.end())
      r_.Fail(item.location, ip, "joint '" + name + "' is listed twice");
    out.push_back(index);
  }
}

}  // namespace screwfem::scene_reading
