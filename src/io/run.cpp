// RunScene (run.h): the run loop of static and dynamic analyses, and what it records.
#include "screwfem/io/run.h"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <optional>

#include "screwfem/assemble/assemble.h"
#include "screwfem/io/progress.h"
#include "screwfem/io/schedule.h"
#include "screwfem/io/vtk.h"
#include "screwfem/io/writers.h"
#include "screwfem/model/errors.h"

namespace screwfem {

namespace {

using Clock = std::chrono::steady_clock;

std::string Format(const char* format, double a, double b = 0.0) {
  char buf[160];
  std::snprintf(buf, sizeof buf, format, a, b);
  return buf;
}

void ValidateSettings(const Scene& scene) {
  const AnalysisSettings& a = scene.analysis;
  const auto require = [](bool ok, const char* field, const std::string& what) {
    if (!ok) throw InputError(std::string(field) + ": " + what);
  };
  const OutputSpec& o = scene.outputs;
  require(std::isfinite(o.interval) && o.interval >= 0.0, "outputs.interval",
          "must be a finite time >= 0 s");
  require(std::isfinite(o.vtk_interval) && o.vtk_interval >= 0.0, "outputs.vtk_interval",
          "must be a finite time >= 0 s");
  if (a.kind == AnalysisKind::kStatic) {
    require(std::isfinite(a.statics.time), "analysis.statics.time", "must be finite");
    return;
  }
  require(std::isfinite(a.start_time), "analysis.start_time", "must be finite");
  require(std::isfinite(a.end_time) && a.end_time >= a.start_time, "analysis.end_time",
          "must be finite and not before start_time");
  require(std::isfinite(a.step) && a.step > 0.0, "analysis.step", "must be a time > 0 s");
  require(a.dynamic.rho_inf >= 0.0 && a.dynamic.rho_inf <= 1.0, "analysis.rho_inf",
          "must lie in [0, 1]");
  require(a.dynamic.max_iterations >= 1, "analysis.max_iterations", "must be at least 1");
  require(a.dynamic.max_halvings >= 0, "analysis.max_halvings", "must be >= 0");
}

// Times of rows (or frames) every `interval` from `start`; every step when interval is 0.
class OutputClock {
 public:
  OutputClock(double start, double interval, double step)
      : start_(start), interval_(interval), tolerance_(1e-6 * step), next_(start) {}
  bool Due(double t) const { return interval_ <= 0.0 || t >= next_ - tolerance_; }
  // After recording at t: the next multiple of the interval after t.
  void Recorded(double t) {
    if (interval_ > 0.0)
      next_ = start_ + (std::floor((t - start_ + tolerance_) / interval_) + 1.0) * interval_;
  }

 private:
  double start_, interval_, tolerance_, next_;
};

// Largest relative rotation |w| of one rod element [rad], on its continued branch (method.md
// §2.7): the branch references are the accepted state's rotations.
double MaxElementRotation(const Data& data) {
  double m = 0.0;
  for (const Vec3& w : data.w_ref) m = std::max(m, w.norm());
  return m;
}

// Largest |phi| over the constraint rows: the relative-frame constraints of the joints
// (JointConstraint, method.md §4.3) and the prescribed drives alpha - q(t) (§4.4). The same
// value as MaxConstraintViolation, which assembles the whole residual (about 15% of a GRM
// time step); this costs one logarithm per joint and is evaluated after every step.
double MaxConstraint(const Model& model, const Data& data, double time) {
  double r = 0.0;
  for (std::size_t jj = 0; jj < model.joints.size(); ++jj) {
    const Joint& j = model.joints[jj];
    if (j.row >= 0) r = std::max(r, JointConstraint(model, data, static_cast<int>(jj)).cwiseAbs().maxCoeff());
    if (j.drive == DriveKind::kPrescribed)
      r = std::max(r, std::abs(data.q_joint(j.coord + j.drive_coord - model.nv_nodes) -
                               j.drive_profile(time)));
  }
  return r;
}

// One call of RunScene: the state, the files and the counters.
class Run {
 public:
  Run(const Scene& scene, const std::string& outdir, const RunOptions& options)
      : scene_(scene), model_(scene.model), options_(options), data_(MakeData(scene.model)),
        wall_start_(Clock::now()), last_summary_(wall_start_) {
    std::error_code ec;
    std::filesystem::create_directories(outdir, ec);
    if (ec) throw InputError("cannot create the output directory " + outdir + ": " + ec.message());
    summary_path_ = outdir + "/summary.json";
    points_.Open(outdir + "/points.csv", PointColumns(scene.outputs.points));
    joints_.Open(outdir + "/joints.csv", JointColumns(model_, scene.outputs.joints));
    if (!WriteFileAtomically(outdir + "/joints.json", JointsDescriptionJson(model_, scene.outputs.joints)))
      throw InputError("cannot write " + outdir + "/joints.json: " + std::strerror(errno));
    if (scene.outputs.vtk) {
      vtk_.emplace();
      vtk_->Open(outdir + "/vtk");
    }
    if (!WriteSummary())
      throw InputError("cannot write " + summary_path_ + ": " + std::strerror(errno));
  }

  void Execute() {
    if (scene_.analysis.kind == AnalysisKind::kStatic)
      RunStatic();
    else
      RunDynamic();
  }

  // Ends the run (if it has not ended yet) and rewrites the summary.
  void Finish(const char* status, std::string message) {
    if (finished_) return;
    finished_ = true;
    // The rows still collected by the writers go to disk before the summary that counts them.
    const bool points_closed = points_.Close();
    const std::string& unwritten = points_closed ? joints_.path() : points_.path();
    if ((!points_closed || !joints_.Close()) && std::string(status) != "failed") {
      status = "failed";
      message = Format("cannot write at t = %.9g s: ", data_.time) + unwritten + ": " +
                std::strerror(errno);
    }
    status_ = status;
    message_ = std::move(message);
    if (progress_) progress_->Finish(data_.time, integ_.steps);
    WriteSummary();
  }

  RunResult Result() const {
    RunResult r;
    r.ok = status_ == std::string("completed");
    r.interrupted = status_ == std::string("interrupted");
    r.end_time = data_.time;
    const bool statics = scene_.analysis.kind == AnalysisKind::kStatic;
    r.steps = statics ? static_.load_steps : integ_.steps;
    r.newton_iterations = integ_.iterations + static_.total_iterations;
    r.max_iterations_per_step = integ_.max_iterations_in_step;
    for (const StaticStep& s : static_.steps)
      r.max_iterations_per_step = std::max(r.max_iterations_per_step, s.iterations);
    r.halvings = integ_.halvings + static_.halvings;
    r.wall_seconds = WallSeconds();
    r.max_constraint_residual = max_constraint_;
    r.max_element_rotation = max_rotation_;
    r.message = message_;
    return r;
  }

 private:
  double WallSeconds() const {
    return std::chrono::duration<double>(Clock::now() - wall_start_).count();
  }

  void RunStatic() {
    const StaticOptions& so = scene_.analysis.statics;
    data_.time = so.time;
    static_ = SolveStatic(model_, data_, so);
    has_static_ = true;
    if (!static_.converged) {
      Finish("failed", Format("static solution failed at load factor %.6g: ", static_.load_factor) +
                           static_.message);
      return;
    }
    max_constraint_ = MaxConstraint(model_, data_, so.time);
    max_rotation_ = MaxElementRotation(data_);
    if (!Record(so.time, true, true)) return;
    if (options_.on_step) {
      if (!FlushRows(so.time)) return;
      options_.on_step(so.time);
    }
    Finish("completed", {});
  }

  void RunDynamic() {
    const AnalysisSettings& a = scene_.analysis;
    data_.time = a.start_time;
    if (a.static_preload) {
      StaticOptions so = a.statics;
      so.time = a.start_time;
      static_ = SolveStatic(model_, data_, so);
      has_static_ = true;
      if (!static_.converged) {
        Finish("failed", Format("static preload at t = %.9g s failed at load factor %.6g: ",
                                a.start_time, static_.load_factor) +
                             static_.message);
        return;
      }
      data_.time = a.start_time;
    }
    std::string why;
    if (!InitializeDynamics(model_, data_, integ_, a.dynamic, &why)) {
      Finish("failed", Format("cannot start the dynamic analysis at t = %.9g s: ", a.start_time) + why);
      return;
    }
    max_constraint_ = MaxConstraint(model_, data_, data_.time);
    max_rotation_ = MaxElementRotation(data_);

    const OutputSpec& o = scene_.outputs;
    OutputClock rows(a.start_time, o.interval, a.step);
    OutputClock frames(a.start_time, o.vtk_interval > 0.0 ? o.vtk_interval : o.interval, a.step);
    if (!Record(data_.time, true, true)) return;
    rows.Recorded(data_.time);
    frames.Recorded(data_.time);
    if (options_.progress) {
      progress_.emplace(stderr, a.start_time, a.end_time);
      progress_->Update(data_.time, 0);
    }

    const StepSchedule schedule(a.start_time, a.end_time, a.step,
                                a.align_steps ? ProfileBreakpoints(model_) : std::vector<double>{});
    while (!schedule.Done(data_.time)) {
      if (options_.stop && options_.stop->load()) {
        Finish("interrupted", Format("interrupted at t = %.9g s; the last recorded row is at t = %.9g s",
                                     data_.time, last_row_time_));
        return;
      }
      const double t_next = schedule.Next(data_.time);
      const StepResult step = Step(model_, data_, integ_, t_next - data_.time);
      if (!step.ok) {
        Finish("failed", step.message);
        return;
      }
      data_.time = t_next;
      max_constraint_ = std::max(max_constraint_, MaxConstraint(model_, data_, t_next));
      max_rotation_ = std::max(max_rotation_, MaxElementRotation(data_));

      const bool last = schedule.Done(t_next);
      const bool row = last || rows.Due(t_next), frame = last || frames.Due(t_next);
      if (row || frame) {
        if (!Record(t_next, row, frame)) return;
        if (row) rows.Recorded(t_next);
        if (frame) frames.Recorded(t_next);
      }
      if (options_.on_step) {
        if (!FlushRows(t_next)) return;
        options_.on_step(t_next);
      }
      if (progress_) progress_->Update(t_next, integ_.steps);
      if (Clock::now() - last_summary_ > std::chrono::seconds(2)) {
        if (!FlushRows(t_next)) return;
        WriteSummary();
      }
    }
    Finish("completed", {});
  }

  // Writes the rows (and the ParaView frame) of the current state; on a write error ends the
  // run as failed and returns false.
  bool Record(double t, bool row, bool frame) {
    if (row) {
      CalcPointRow(model_, data_, scene_.outputs.points, &row_);
      if (!points_.WriteRow(t, row_)) return WriteFailed(points_.path(), t);
      CalcJointRow(model_, data_, scene_.outputs.joints, &row_);
      if (!joints_.WriteRow(t, row_)) return WriteFailed(joints_.path(), t);
      last_row_time_ = t;
    }
    if (frame && vtk_ && !vtk_->WriteFrame(model_, data_, t))
      return WriteFailed(vtk_->dir() + "/frame files", t);
    return true;
  }

  // Writes the rows collected so far to the files; on a write error ends the run as failed.
  bool FlushRows(double t) {
    if (!points_.Flush()) return WriteFailed(points_.path(), t);
    if (!joints_.Flush()) return WriteFailed(joints_.path(), t);
    return true;
  }

  bool WriteFailed(const std::string& path, double t) {
    Finish("failed", Format("cannot write at t = %.9g s: ", t) + path + ": " + std::strerror(errno));
    return false;
  }

  // The summary of the run so far (run.h); false if it could not be written.
  bool WriteSummary() {
    last_summary_ = Clock::now();
    const AnalysisSettings& a = scene_.analysis;
    const DynamicOptions& d = a.dynamic;
    const StaticOptions& s = a.statics;
    const bool statics = a.kind == AnalysisKind::kStatic;
    const double wall = WallSeconds();
    const double simulated = statics ? 0.0 : data_.time - a.start_time;
    JsonWriter j;
    j.BeginObject();
    j.Field("format", "screwfem run summary 1");
    j.Key("scene").BeginObject().Field("source", scene_.source).Field("name", scene_.name).EndObject();
    j.Field("status", status_).Field("message", message_);

    j.Key("settings").BeginObject();
    j.Field("analysis", statics ? "static" : "dynamic");
    if (!statics) {
      j.Field("start_time", a.start_time).Field("end_time", a.end_time).Field("step", a.step);
      j.Field("align_steps", a.align_steps).Field("static_preload", a.static_preload);
      j.Field("rho_inf", d.rho_inf).Field("max_iterations", d.max_iterations);
      j.Field("max_halvings", d.max_halvings);
      j.Field("increment_tolerance", d.increment_tolerance);
      j.Field("constraint_tolerance", d.constraint_tolerance);
      j.Field("residual_tolerance", d.residual_tolerance);
      j.Field("use_tangent_operator", d.use_tangent_operator);
      j.Field("newton", d.newton_matrix == NewtonMatrix::kEveryIteration ? "full" : "simplified");
      j.Field("refresh_ratio", d.refresh_ratio);
      j.Field("predictor", d.predictor == Predictor::kZeroAcceleration   ? "zero"
                           : d.predictor == Predictor::kLastAcceleration ? "last"
                                                                          : "adaptive");
      j.Field("convergence",
              d.convergence == ConvergenceTest::kMeasured ? "measured" : "estimated");
    }
    if (statics || a.static_preload) {
      j.Key("statics").BeginObject();
      j.Field("time", statics ? s.time : a.start_time).Field("load_steps", s.load_steps);
      j.Field("max_halvings", s.max_halvings).Field("max_iterations", s.max_iterations);
      j.Field("residual_tolerance", s.residual_tolerance);
      j.Field("increment_tolerance", s.increment_tolerance);
      j.Field("constraint_tolerance", s.constraint_tolerance);
      j.EndObject();
    }
    j.Field("rod_inertia", model_.rod_inertia == RodInertia::kExact ? "exact" : "constant");
    j.Key("gravity").BeginArray();
    for (int i = 0; i < 3; ++i) j.Number(model_.gravity(i));
    j.EndArray();
    j.Field("output_interval", scene_.outputs.interval);
    j.Field("vtk", scene_.outputs.vtk).Field("vtk_interval", scene_.outputs.vtk_interval);
    j.EndObject();

    long free_nodes = 0;
    for (const Node& n : model_.nodes) free_nodes += n.dof >= 0 ? 1 : 0;
    j.Key("counts").BeginObject();
    j.Field("nodes", static_cast<long>(model_.nodes.size())).Field("free_nodes", free_nodes);
    j.Field("rods", static_cast<long>(model_.rods.size()));
    j.Field("elements", static_cast<long>(model_.elements.size()));
    j.Field("rigid_bodies", static_cast<long>(model_.bodies.size()));
    j.Field("joints", static_cast<long>(model_.joints.size()));
    j.Field("point_loads", static_cast<long>(model_.point_loads.size()));
    j.Field("nv", model_.nv).Field("nc", model_.nc);
    j.Field("redundant_constraints", static_cast<long>(model_.redundant_rows.size()));
    j.Field("bandwidth", model_.bandwidth);
    j.EndObject();

    j.Key("outputs").BeginObject();
    j.Key("points").BeginArray();
    for (const OutputPoint& p : scene_.outputs.points) j.String(p.name);
    j.EndArray();
    j.Key("joints").BeginArray();
    for (const OutputJoint& oj : scene_.outputs.joints) j.String(oj.name);
    j.EndArray();
    j.Field("rows", points_.rows()).Field("last_row_time", last_row_time_);
    j.Field("vtk_frames", vtk_ ? vtk_->frames() : 0);
    j.EndObject();

    j.Field("time", data_.time);
    j.Field("steps", integ_.steps);
    j.Field("newton_iterations", integ_.iterations);
    j.Field("max_iterations_per_step", integ_.max_iterations_in_step);
    j.Field("step_halvings", integ_.halvings);
    j.Field("matrix_factorizations", integ_.factorizations);
    j.Field("step_retries", integ_.retries);
    j.Field("estimated_convergences", integ_.estimated_convergences);
    if (has_static_) {
      j.Key("static_solution").BeginObject();
      j.Field("converged", static_.converged).Field("load_factor", static_.load_factor);
      j.Field("load_steps", static_.load_steps).Field("newton_iterations", static_.total_iterations);
      j.Field("halvings", static_.halvings);
      j.EndObject();
    }
    j.Field("wall_seconds", wall);
    j.Field("real_time_factor", wall > 0.0 && !statics ? simulated / wall : 0.0);
    j.Field("max_constraint_residual", max_constraint_);
    j.Field("max_element_rotation", max_rotation_);
    j.Key("warnings").BeginArray();
    for (const std::string& w : model_.warnings) j.String(w);
    j.EndArray();
    j.EndObject();
    return WriteFileAtomically(summary_path_, j.str());
  }

  const Scene& scene_;
  const Model& model_;
  const RunOptions& options_;
  std::string summary_path_;
  Data data_;
  Integrator integ_;
  StaticResult static_;
  bool has_static_ = false;
  CsvWriter points_, joints_;
  std::optional<VtkWriter> vtk_;
  std::optional<ProgressBar> progress_;
  std::vector<double> row_;
  Clock::time_point wall_start_, last_summary_;
  double max_constraint_ = 0.0;
  double max_rotation_ = 0.0;  // largest relative rotation of one rod element so far [rad]
  double last_row_time_ = NAN;
  std::string status_ = "running", message_;
  bool finished_ = false;
};

}  // namespace

RunResult RunScene(const Scene& scene, const std::string& outdir, const RunOptions& options) {
  ValidateSettings(scene);
  ValidateOutputs(scene.model, scene.outputs);
  Run run(scene, outdir, options);
  try {
    run.Execute();
  } catch (const std::exception& e) {
    run.Finish("failed", std::string("internal error: ") + e.what());
    throw;
  }
  return run.Result();
}

}  // namespace screwfem
