// Recording (recording.h): the files of a run, written as a simulation advances.
#include "screwfem/io/recording.h"

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <optional>
#include <vector>

#include <dirent.h>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include "screwfem/assemble/assemble.h"
#include "screwfem/assemble/outputs.h"
#include "screwfem/elements/contact.h"
#include "screwfem/elements/joint.h"
#include "screwfem/elements/shape_pair.h"
#include "screwfem/io/progress.h"
#include "screwfem/solve/initial_state.h"
#include "screwfem/solve/rest.h"
#include "screwfem/solve/schedule.h"
#include "screwfem/io/vtk.h"
#include "screwfem/io/writers.h"
#include "screwfem/model/errors.h"

namespace screwfem {

namespace {

using Clock = std::chrono::steady_clock;

// The outputs to record (throws InputError naming the field).
void ValidateRecordedOutputs(const Model& model, const OutputSpec& o) {
  const auto require = [](bool ok, const char* field, const std::string& what) {
    if (!ok) throw InputError(std::string(field) + ": " + what);
  };
  require(std::isfinite(o.interval) && o.interval >= 0.0, "outputs.interval",
          "must be a finite time >= 0 s");
  require(o.max_rows >= 1 && o.max_rows <= kMaxMaxRows, "outputs.max_rows",
          "must be a whole number from 1 to " + std::to_string(kMaxMaxRows));
  require(std::isfinite(o.vtk_interval) && o.vtk_interval >= 0.0, "outputs.vtk_interval",
          "must be a finite time >= 0 s");
  require(IsEnumValue(o.vtk_format), "outputs.vtk_format",
          "must be " + EnumNameAlternatives<VtkFormat>());
  require(!o.rod_fields || o.rod_fields_interval < 0.0 || std::isfinite(o.rod_fields_interval),
          "outputs.rod_fields",
          "the interval must be a finite time >= 0 s (or < 0: at the rows of points.csv)");
  ValidateOutputs(model, o);
}

// About how many ParaView frames a run writes (a reservation, so that writing them allocates
// nothing): one per frame interval (or step), the first and the last, and one per profile
// breakpoint for steps shortened to land on them (static analyses: one per load step);
// capped, since it is only a hint.
int ExpectedFrames(const Scene& scene, const OutputSpec& o) {
  const AnalysisSettings& a = scene.analysis;
  if (a.kind == AnalysisKind::kStatic) return std::clamp(a.statics.load_steps + 1, 1, 1000000);
  const double interval = std::max(o.vtk_interval > 0.0 ? o.vtk_interval : o.interval, a.step);
  const double frames =
      std::ceil((a.end_time - a.start_time) / interval) + 2.0 +
      static_cast<double>(a.align_steps ? ProfileBreakpoints(scene.model).size() : 0);
  return static_cast<int>(std::clamp(frames, 1.0, 1e6));
}

// The output times of one clock of a dynamic analysis (EstimateOutputs, run.h).
double EstimateTimes(const Scene& scene, double interval) {
  const AnalysisSettings& a = scene.analysis;
  const double span = std::max(a.end_time - a.start_time, 0.0);
  // The start, each multiple of the interval after it and the end (when it is no multiple).
  const double clock = interval > 0.0 ? std::ceil(span / interval * (1.0 - 1e-12)) + 1.0 : NAN;
  if (a.adaptive_steps) return clock;
  const double breakpoints =
      a.align_steps ? static_cast<double>(ProfileBreakpoints(scene.model).size()) : 0.0;
  const double steps = std::ceil(span / a.step * (1.0 - 1e-12)) + breakpoints;
  if (interval <= a.step) return steps + 1.0;
  return std::min(clock, steps + 1.0);
}

// "SIGINT", ... for the signals a run is stopped by; nullptr for others and 0.
const char* SignalName(int signal) {
  switch (signal) {
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
    case SIGHUP:
      return "SIGHUP";
    default:
      return nullptr;
  }
}

// Largest relative rotation |w| of one rod element [rad], on its continued branch (elements/rod.h): the branch references are the accepted state's rotations.
double MaxElementRotation(const Data& data) {
  double m = 0.0;
  for (const Vec3& w : data.w_ref) m = std::max(m, w.norm());
  return m;
}

// Rows collected before the tables are written (writers.h, CsvWriter).
constexpr std::size_t kRowBatchBytes = 64 * 1024;

// The names of screwfem's files in `folder` (writers.h, IsOutputFileName; `vtk`: its vtk
// subfolder), sorted. Throws InputError (OutputFolder::CheckNotLink) when one of
// them is a symbolic link or not a regular file.
std::vector<std::string> OwnFiles(const OutputFolder& folder, bool vtk) {
  std::vector<std::string> own;
  if (!vtk) {
    for (const char* name : kOutputFiles)
      if (folder.CheckNotLink(name)) own.emplace_back(name);
    return own;
  }
  const int fd = ::dup(folder.fd());
  DIR* d = fd >= 0 ? ::fdopendir(fd) : nullptr;
  if (d == nullptr) {
    const int error = errno;
    if (fd >= 0) ::close(fd);
    throw InputError("cannot read directory " + folder.path() + ": " + std::strerror(error));
  }
  ::rewinddir(d);
  while (const dirent* e = ::readdir(d))
    if (IsOutputFileName(e->d_name, true)) own.emplace_back(e->d_name);
  ::closedir(d);
  std::sort(own.begin(), own.end());
  for (const std::string& name : own) folder.CheckNotLink(name.c_str());
  return own;
}

// Refuses a directory that holds the files of an earlier run, unless `replace`: then removes
// them: screwfem's own files only (writers.h, kOutputFiles, kVtkFiles and the frames), each by
// its name in the folder (unlinkat), and vtk/ when that leaves it empty, so that no stale
// table or frame survives and nothing else is touched. A symbolic link at one of those names,
// or a vtk/ that is a link, is refused (InputError naming it), with or without `replace`:
// nothing is followed.
void PrepareOutputDirectory(const OutputFolder& folder, bool replace) {
  const std::vector<std::string> own = OwnFiles(folder, false);
  std::vector<std::string> own_vtk;
  OutputFolder vtk;
  if (folder.CheckNotLink(kVtkFolder, true)) {
    vtk.OpenSubfolder(folder, kVtkFolder, false);
    own_vtk = OwnFiles(vtk, true);
  }
  if (own.empty() && own_vtk.empty()) return;
  if (!replace) {
    std::vector<std::string> all = own;
    for (const std::string& f : own_vtk) all.push_back(std::string(kVtkFolder) + "/" + f);
    std::string list;
    for (std::size_t i = 0; i < all.size() && i < 4; ++i) list += (i > 0 ? ", " : "") + all[i];
    if (all.size() > 4) list += ", ...";
    throw InputError("output directory " + folder.path() +
                     " holds the results of an earlier run (" + list +
                     "); choose another directory, or replace them with --force (Python: "
                     "run_scene(..., force=True)), which removes screwfem's files only");
  }
  for (const std::string& f : own)
    if (!folder.Remove(f.c_str()) && errno != ENOENT)
      throw InputError("cannot remove " + folder.path() + "/" + f + ": " + std::strerror(errno));
  for (const std::string& f : own_vtk)
    if (!vtk.Remove(f.c_str()) && errno != ENOENT)
      throw InputError("cannot remove " + vtk.path() + "/" + f + ": " + std::strerror(errno));
  if (vtk.is_open()) ::unlinkat(folder.fd(), kVtkFolder, AT_REMOVEDIR);  // only when empty
}

}  // namespace

OutputEstimate EstimateOutputs(const Scene& scene, const OutputSpec& o) {
  OutputEstimate e;
  const AnalysisSettings& a = scene.analysis;
  if (a.kind == AnalysisKind::kStatic) {
    e.rows = static_cast<double>(a.statics.load_steps) + 1.0;
    e.frames = o.vtk ? e.rows : 0.0;
    return e;
  }
  e.rows = EstimateTimes(scene, o.interval);
  if (o.vtk) e.frames = EstimateTimes(scene, o.vtk_interval > 0.0 ? o.vtk_interval : o.interval);
  if (o.rod_fields && o.rod_fields_interval >= 0.0)
    e.field_times = EstimateTimes(scene, o.rod_fields_interval);
  return e;
}

void CheckOutputRows(const Scene& scene, const OutputSpec& o) {
  const OutputEstimate e = EstimateOutputs(scene, o);
  const double limit = static_cast<double>(o.max_rows);
  const bool statics = scene.analysis.kind == AnalysisKind::kStatic;
  const auto check = [&](double count, const char* what, const char* setting) {
    if (!(count > limit)) return;  // (NaN: not estimated)
    throw InputError(FormatNumbers("outputs.max_rows: the run would record about %.0f ", count) +
                     what + ", above the limit of " + std::to_string(o.max_rows) +
                     " (outputs.max_rows); " +
                     (statics ? std::string("use fewer load steps (analysis.statics.load_steps)")
                              : std::string("record less often (") + setting + ")") +
                     " or raise outputs.max_rows");
  };
  check(e.rows, "rows in each table", "outputs.interval");
  check(e.field_times, "rod_fields.csv times", "outputs.rod_fields");
  check(e.frames, "ParaView frames",
        o.vtk_interval > 0.0 ? "outputs.vtk_interval" : "outputs.vtk_interval or outputs.interval");
}

// Types of Recording::Impl's members (a named namespace: Impl has external linkage).
namespace recording_internal {

// Times of rows (or frames) every `interval` from `start`; every step when interval is 0.
class OutputClock {
 public:
  OutputClock(double start, double interval, double step)
      : start_(start), interval_(interval), tolerance_(1e-6 * step), next_(start) {}
  bool Due(double t) const { return interval_ <= 0.0 || t >= next_ - tolerance_; }
  // The next due time (infinity when rows follow the steps): adaptive runs interpolate the
  // state there when it falls inside a step.
  double Next() const { return interval_ > 0.0 ? next_ : INFINITY; }
  // After recording at t: the next multiple of the interval after t.
  void Recorded(double t) {
    if (interval_ > 0.0)
      next_ = start_ + (std::floor((t - start_ + tolerance_) / interval_) + 1.0) * interval_;
  }

 private:
  double start_, interval_, tolerance_, next_;
};

// OUTDIR/.screwfem.lock: an exclusive flock(2) held by the running run, with its process id
// as the file's text. The kernel releases it when the file is closed, also when the process
// dies (a crash, SIGKILL), so a stale lock file never blocks a run.
class OutputLock {
 public:
  OutputLock() = default;
  OutputLock(const OutputLock&) = delete;
  OutputLock& operator=(const OutputLock&) = delete;
  ~OutputLock() {
    if (fd_ >= 0) ::close(fd_);
  }

  // Throws InputError naming the other process when another run holds the directory, and
  // when the lock file is a symbolic link, a hard link of another file or not a regular file
  // (it is written: the process id).
  void Acquire(const OutputFolder& folder) {
    const std::string dir = folder.path();
    fd_ = ::openat(folder.fd(), kOutputLockFile,
                   O_RDWR | O_CREAT | O_NOFOLLOW | O_CLOEXEC | O_NONBLOCK, 0644);
    struct stat st {};
    int open_error = fd_ < 0 ? errno : 0;
    if (fd_ >= 0 && ::fstat(fd_, &st) != 0) open_error = errno;
    if (fd_ >= 0 && open_error == 0 && !S_ISREG(st.st_mode)) open_error = EISDIR;
    if (fd_ >= 0 && open_error == 0 && st.st_nlink > 1) open_error = EMLINK;
    if (open_error != 0) {
      if (fd_ >= 0) ::close(fd_);
      fd_ = -1;
      throw InputError(folder.CreateError(kOutputLockFile, open_error));
    }
    const std::string path = dir + "/" + kOutputLockFile;
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      const int error = errno;
      char pid[32] = {};
      const ssize_t n = ::pread(fd_, pid, sizeof pid - 1, 0);
      std::string holder = n > 0 ? std::string(pid, static_cast<std::size_t>(n)) : "";
      while (!holder.empty() && (holder.back() == '\n' || holder.back() == ' ')) holder.pop_back();
      ::close(fd_);
      fd_ = -1;
      if (error == EWOULDBLOCK)
        throw InputError("output directory " + dir +
                         " is in use by another screwfem run (process " +
                         (holder.empty() ? std::string("unknown") : holder) +
                         "); wait for it to end, stop it, or choose another directory");
      throw InputError("cannot lock " + path + ": " + std::strerror(error));
    }
    const std::string pid = std::to_string(::getpid()) + "\n";
    if (::ftruncate(fd_, 0) != 0 || ::pwrite(fd_, pid.data(), pid.size(), 0) < 0) {
      // The lock holds without the process id; only the message of a second run loses it.
    }
  }

 private:
  int fd_ = -1;
};

}  // namespace recording_internal

using recording_internal::OutputClock;
using recording_internal::OutputLock;

// One recording: the files, the output clocks, the counters and the summary.
class Recording::Impl {
 public:
  Impl(const Scene& scene, const OutputSpec& outputs, const Model& model, Data& data,
       Integrator& integrator, const std::string& outdir, const RunOptions& options)
      : scene_(scene),
        outputs_(outputs),
        model_(model),
        options_(options),
        data_(data),
        integ_(integrator),
        start_time_(scene.analysis.start_time),
        wall_start_(Clock::now()),
        last_summary_(wall_start_) {
    ValidateRecordedOutputs(model, outputs_);
    CheckOutputRows(scene, outputs_);
    folder_.Open(outdir, true);
    lock_.Acquire(folder_);
    PrepareOutputDirectory(folder_, options.replace_results);
    try {
      points_.Open(folder_, kPointsFile, StaticColumns(PointColumns(outputs_.points)));
      joints_.Open(folder_, kJointsFile, StaticColumns(JointColumns(model_, outputs_.joints)));
      // reactions.csv and energy.csv unless the outputs turn them off (then not computed).
      if (outputs_.reactions) {
        reactions_.Open(folder_, kReactionsFile, StaticColumns(ReactionColumns(model_)));
        tables_[num_tables_++] = &reactions_;
      }
      if (outputs_.energy) {
        energy_.Open(folder_, kEnergyFile, StaticColumns(EnergyColumns()));
        tables_[num_tables_++] = &energy_;
      }
      // Tendons and force elements: their tables only when the model has them.
      if (!model_.tendons.empty()) {
        tendons_.Open(folder_, kTendonsFile, StaticColumns(TendonColumns(model_)));
        tables_[num_tables_++] = &tendons_;
      }
      if (!model_.force_elements.empty()) {
        forces_.Open(folder_, kForcesFile, StaticColumns(ForceColumns(model_)));
        tables_[num_tables_++] = &forces_;
      }
      if (!model_.actuators.empty()) {
        actuators_.Open(folder_, kActuatorsFile, StaticColumns(ActuatorColumns(model_)));
        tables_[num_tables_++] = &actuators_;
      }
      // Rod fields (long format, one row per element at each output time, written as one
      // block), at the rows of points.csv or at an interval of its own.
      if (outputs_.rod_fields) {
        rod_fields_.Open(folder_, kRodFieldsFile, StaticColumns(RodFieldColumns()));
        // Room for a batch and two more blocks of up to 24 characters a value.
        rod_fields_.Reserve(kRowBatchBytes +
                            2 * model_.elements.size() * (kRodFieldValues + 2) * 24);
        lead_.reserve(1);
        tables_[num_tables_++] = &rod_fields_;
      }
      // Contacts: one row per active pair (long format).
      if (!model_.contact_pairs.empty()) {
        contacts_.Open(folder_, kContactsFile, StaticColumns(ContactColumns()));
        tables_[num_tables_++] = &contacts_;
      }
      if (MayHaveShapePairs(model_)) {
        pair_contacts_.Open(folder_, kPairContactsFile, StaticColumns(PairContactColumns()));
        tables_[num_tables_++] = &pair_contacts_;
      }
      // Settling (kinetic energy, contacts, deepest overlap): with contact.
      if (HasContact(model_)) {
        settling_.Open(folder_, kSettlingFile, StaticColumns(SettlingColumns()));
        tables_[num_tables_++] = &settling_;
      }
      if (outputs_.vtk) {
        vtk_.emplace();
        vtk_->Open(folder_, model_, outputs_.vtk_format, ExpectedFrames(scene, outputs_),
                   outputs_.rod_fields);
      }
      if (scene_.analysis.kind == AnalysisKind::kStatic)
        event_load_factors_.reserve(static_cast<std::size_t>(ExpectedFrames(scene, outputs_)));
      if (!WriteSummary())
        throw InputError("cannot write " + folder_.path() + "/" + kSummaryFile + ": " +
                         std::strerror(errno));
      if (!WriteFileAtomically(folder_, kJointsDescriptionFile,
                               JointsDescriptionJson(model_, outputs_.joints)))
        throw InputError("cannot write " + folder_.path() + "/" + kJointsDescriptionFile + ": " +
                         std::strerror(errno));
    } catch (const InputError&) {
      // No header-only tables without a summary that explains them.
      for (std::size_t i = 0; i < num_tables_; ++i) tables_[i]->Close();
      try {
        PrepareOutputDirectory(folder_, true);
      } catch (const InputError&) {
        // (a link planted meanwhile: left alone)
      }
      throw;
    }
  }
  // Ends the run (if it has not ended yet): the rows still collected go to disk, then the
  // ParaView collection (listing the frames on disk) and the summary that counts them.
  void Finish(const char* status, std::string message) {
    if (finished_) return;
    finished_ = true;
    const bool failed_before = io_error_ || std::string(status) == "failed";
    const CsvWriter* w = CsvWriter::FlushTogether(tables_.data(), num_tables_);
    if (w && !failed_before) {
      status = "failed";
      message = "cannot write at " + When(data_.time, load_factor_) + ": " + w->path() + ": " +
                std::strerror(errno);
      io_error_ = true;
    }
    bool closed = true;
    for (std::size_t i = 0; i < num_tables_; ++i) closed = tables_[i]->Close() && closed;
    if (!closed && !failed_before && !io_error_) {
      status = "failed";
      message = "cannot close the tables: " + std::string(std::strerror(errno));
      io_error_ = true;
    }
    if (vtk_ && !vtk_->WriteCollection() && std::string(status) != "failed") {
      status = "failed";
      message = "cannot write " + vtk_->dir() + "/motion.pvd: " + std::strerror(errno);
      io_error_ = true;
    }
    status_ = status;
    message_ = std::move(message);
    if (io_error_ && points_.failed())
      message_ += points_.rows() == 0
                      ? std::string("; the tables hold no rows")
                      : "; the tables hold the " + std::to_string(points_.rows()) + " rows up to " +
                            When(points_.last_time(), LoadFactorOfEvent(points_.last_key()));
    if (progress_) progress_->Finish(data_.time, integ_.steps);
    WriteSummary();
  }

  // "t = 0.25 s", or in static analyses (where every row has the same t) "load factor
  // λ = 0.5".
  std::string When(double t, double load_factor) const {
    if (scene_.analysis.kind == AnalysisKind::kStatic)
      return FormatNumbers("load factor λ = %.9g", load_factor);
    return FormatNumbers("t = %.9g s", t);
  }
  // Static analyses: the load factor of the output event `key` (Record's sequence number).
  double LoadFactorOfEvent(long long key) const {
    return key >= 0 && key < static_cast<long long>(event_load_factors_.size())
               ? event_load_factors_[static_cast<std::size_t>(key)]
               : load_factor_;
  }

  RunResult Result() const {
    RunResult r;
    r.ok = status_ == std::string("completed");
    r.interrupted = status_ == std::string("interrupted") || status_ == std::string("terminated");
    r.signal = signal_;
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
    r.io_error = io_error_;
    if (statics) r.load_factor = has_static_ ? static_.load_factor : load_factor_;
    return r;
  }
  // Dynamic analyses: the first row and frame, the output clocks from there.
  void StopAtRest(const RestCriterion& c) { stop_at_rest_ = c; }
  bool Start() {
    start_time_ = data_.time;
    max_constraint_ = CalcMaxJointConstraint(model_, data_, data_.time);
    max_rotation_ = MaxElementRotation(data_);
    const AnalysisSettings& a = scene_.analysis;
    if (a.adaptive_steps) dense_ = data_;  // the interpolated state's storage, before stepping
    rows_.emplace(start_time_, outputs_.interval, a.step);
    frames_.emplace(start_time_,
                    outputs_.vtk_interval > 0.0 ? outputs_.vtk_interval : outputs_.interval,
                    a.step);
    if (FieldsApart()) fields_.emplace(start_time_, outputs_.rod_fields_interval, a.step);
    if (stop_at_rest_.enabled) {
      // Not at rest before the inputs stop changing: the last profile breakpoint and the
      // last row of a run-time input table.
      double earliest = start_time_;
      for (double b : ProfileBreakpoints(model_)) earliest = std::max(earliest, b);
      if (!options_.inputs.times.empty())
        earliest = std::max(earliest, options_.inputs.times.back());
      rest_.emplace(stop_at_rest_, earliest);
    }
    if (!Record(data_.time, true, true, FieldsApart())) return false;
    rows_->Recorded(data_.time);
    frames_->Recorded(data_.time);
    if (fields_) fields_->Recorded(data_.time);
    if (options_.progress) {
      progress_.emplace(stderr, a.start_time, a.end_time);
      progress_->Update(data_.time, 0);
    }
    return true;
  }
  bool started() const { return rows_.has_value(); }

  // The stepping loop's side (recording.h): the inputs held over a step, the rows and frames
  // due at its end or (error-controlled steps) interpolated inside it, and after each step the
  // largest constraint residual and rotation, the on_step callback, the progress bar and the
  // summary every 2 s.
  void BeforeStep(double t_inputs) { SetInputsAt(options_.inputs, t_inputs, data_); }
  double NextOutputTime() const {
    if (!rows_) return INFINITY;
    const double next = std::min(rows_->Next(), frames_->Next());
    return fields_ ? std::min(next, fields_->Next()) : next;
  }
  // The rows and frames due strictly inside the last AdaptiveStep, from the state
  // interpolated on the Lie group (InterpolateStep, docs/numerics.md); false if writing failed.
  bool OutputInsideStep(double t) {
    InterpolateStep(model_, data_, integ_, t, dense_);
    const bool row = rows_->Next() <= t, frame = frames_->Next() <= t;
    const bool fields = fields_ && fields_->Next() <= t;
    if (!Record(t, row, frame, fields, dense_)) return false;
    if (row) rows_->Recorded(t);
    if (frame) frames_->Recorded(t);
    if (fields) fields_->Recorded(t);
    return true;
  }
  bool AfterStep(bool last) {
    const double t = data_.time;
    max_constraint_ = std::max(max_constraint_, CalcMaxJointConstraint(model_, data_, t));
    max_rotation_ = std::max(max_rotation_, MaxElementRotation(data_));
    // analysis.stop_at_rest: the state at rest is the run's last (its row and frame).
    const bool at_rest = !last && rest_ && rest_->Update(model_, data_);
    last = last || at_rest;
    const bool row = last || rows_->Due(t), frame = last || frames_->Due(t);
    const bool fields = fields_ && (last || fields_->Due(t));
    if (row || frame || fields) {
      if (!Record(t, row, frame, fields)) return false;
      if (row) rows_->Recorded(t);
      if (frame) frames_->Recorded(t);
      if (fields) fields_->Recorded(t);
    }
    if (options_.on_step) {
      if (!FlushRows(t)) return false;
      options_.on_step(t);
    }
    if (progress_) progress_->Update(t, integ_.steps);
    if (at_rest) {
      rest_time_ = t;
      Finish("completed",
             FormatNumbers("at rest at t = %.9g s (analysis.stop_at_rest: every node slower than "
                           "%.3g m/s ",
                           t, rest_->criterion().speed) +
                 FormatNumbers("and %.3g rad/s since t = %.9g s)", rest_->criterion().angular_speed,
                               rest_->since()));
      return false;
    }
    if (Clock::now() - last_summary_ > std::chrono::seconds(2)) {
      if (!FlushRows(t)) return false;
      WriteSummary();
    }
    return true;
  }

  // Static analyses (recording.h): each converged load step's rows and frame (the frame's
  // time is the load factor, Record).
  bool RecordStaticStep(double t, double load_factor) {
    load_factor_ = load_factor;
    if (finished_) return true;
    // The converged step's residual and rotation: what the summary reports when a write error
    // ends the path before its solution (RecordStaticSolution sets them otherwise).
    max_constraint_ = CalcMaxJointConstraint(model_, data_, t);
    max_rotation_ = MaxElementRotation(data_);
    return Record(t, true, true);
  }
  void SetStaticResult(const StaticResult& result) {
    static_ = result;
    has_static_ = true;
    if (finished_) WriteSummary();  // ended by a write error on the path: the solution's count
  }
  bool RecordStaticSolution(double t, bool row) {
    max_constraint_ = CalcMaxJointConstraint(model_, data_, t);
    max_rotation_ = MaxElementRotation(data_);
    load_factor_ = static_.load_factor;
    if (row && !Record(t, true, true)) return false;  // else the last step's row and frame
    if (options_.on_step) {
      if (!FlushRows(t)) return false;
      options_.on_step(t);
    }
    return true;
  }

  StopRequest StopWhenFinished(const StopRequest& stop) {
    outer_stop_ = stop;
    StopRequest r;
    r.flag = stop.flag;  // its signal number stays the request's
    r.context = this;
    r.poll = [](void* context) {
      const Impl* impl = static_cast<const Impl*>(context);
      const StopRequest& o = impl->outer_stop_;
      return impl->finished_ || (o.poll != nullptr && o.poll(o.context));
    };
    return r;
  }

  // The current state's row and frame unless it was the last recorded (recording.h).
  bool RecordFinalState() {
    if (finished_ || !rows_ || last_row_time_ == data_.time) return true;
    const double t = data_.time;
    if (!Record(t, true, true, fields_.has_value())) return false;
    rows_->Recorded(t);
    frames_->Recorded(t);
    if (fields_) fields_->Recorded(t);
    return true;
  }

  bool finished() const { return finished_; }
  double last_row_time() const { return last_row_time_; }

  // Ends the run after a stop request: "interrupted" (SIGINT, a Python KeyboardInterrupt or a
  // flag without a signal number) or "terminated" (SIGTERM, SIGHUP), naming the signal.
  void Interrupted(int signal, const std::string& when) {
    signal_ = signal;
    const char* name = SignalName(signal_);
    const bool terminated = signal_ == SIGTERM || signal_ == SIGHUP;
    std::string message = terminated ? "terminated" : "interrupted";
    if (name != nullptr) message += std::string(" by ") + name;
    Finish(terminated ? "terminated" : "interrupted", message + " " + when);
  }

 private:
  double WallSeconds() const {
    return std::chrono::duration<double>(Clock::now() - wall_start_).count();
  }

  // Static analyses: a load_factor column after t in points.csv and joints.csv.
  std::vector<std::string> StaticColumns(std::vector<std::string> columns) const {
    if (scene_.analysis.kind == AnalysisKind::kStatic)
      columns.insert(columns.begin(), "load_factor");
    return columns;
  }

  // rod_fields.csv at an interval of its own (dynamic analyses), rather than with the rows
  // of points.csv.
  bool FieldsApart() const {
    return outputs_.rod_fields && outputs_.rod_fields_interval >= 0.0 &&
           scene_.analysis.kind != AnalysisKind::kStatic;
  }

  // Writes the rows (and the ParaView frame) of the current state, and with `fields` the rows
  // of rod_fields.csv at its own interval (FieldsApart; else they come with the rows); on a
  // write error ends the run as failed and returns false. Static analyses give each frame the
  // load factor as its time (motion.pvd's timestep and the frame's TimeValue), since every
  // state of the path has the same time.
  bool Record(double t, bool row, bool frame, bool fields = false) {
    return Record(t, row, frame, fields, data_);
  }
  bool Record(double t, bool row, bool frame, bool fields, const Data& data) {
    const bool statics = scene_.analysis.kind == AnalysisKind::kStatic;
    // The runtime bound (outputs.max_rows): a run that would write more rows or frames than
    // the limit ends, as failed, before it does.
    const long limit = outputs_.max_rows;
    if (row && row_events_ >= limit) return LimitReached("rows of the tables", t);
    if (fields && FieldsApart() && field_events_ >= limit)
      return LimitReached("rod field times", t);
    if (frame && vtk_ && vtk_->frames() >= limit) return LimitReached("ParaView frames", t);
    const bool fields_now = (row && outputs_.rod_fields && !FieldsApart()) || fields;
    if (row || fields_now) {
      // One output event: its rows in every table share the key, so that a write error cuts
      // every table at the same event (FlushTogether).
      const long long key = events_++;
      if (statics) event_load_factors_.push_back(load_factor_);
      if (fields_now) {
        CalcRodFieldRows(model_, data, -1, statics ? load_factor_ : 1.0, &row_);
        if (statics) lead_.assign(1, load_factor_);
        rod_fields_.WriteRows(t, lead_, row_, kRodFieldValues, key);
        if (fields) ++field_events_;
      }
      if (row) {
        ++row_events_;
        const double lf = statics ? load_factor_ : 1.0;
        CalcPointRow(model_, data, outputs_.points, &row_);
        points_.WriteRow(t, WithLoadFactor(row_), key);
        CalcJointRow(model_, data, outputs_.joints, &row_);
        joints_.WriteRow(t, WithLoadFactor(row_), key);
        if (outputs_.reactions) {
          CalcReactionRow(model_, data, &row_);
          reactions_.WriteRow(t, WithLoadFactor(row_), key);
        }
        double kinetic = NAN;  // from energy.csv's row, for settling.csv's
        if (outputs_.energy) {
          CalcEnergyRow(model_, data, &row_);
          kinetic = row_[0];
          energy_.WriteRow(t, WithLoadFactor(row_), key);
        }
        if (tendons_.path().size() > 0) {
          CalcTendonRow(model_, data, &row_, lf);
          tendons_.WriteRow(t, WithLoadFactor(row_), key);
        }
        if (forces_.path().size() > 0) {
          CalcForceRow(model_, data, &row_, lf);
          forces_.WriteRow(t, WithLoadFactor(row_), key);
        }
        if (actuators_.path().size() > 0) {
          CalcActuatorRow(model_, data, t, &row_);
          actuators_.WriteRow(t, WithLoadFactor(row_), key);
        }
        if (contacts_.path().size() > 0) {
          for (int i = 0; i < static_cast<int>(model_.contact_pairs.size()); ++i)
            if (CalcContactRow(model_, data, i, &row_))
              contacts_.WriteRow(t, WithLoadFactor(row_), key);
        }
        if (pair_contacts_.path().size() > 0) {
          for (int i = 0; i < data.num_shape_pairs; ++i)
            if (CalcPairContactRow(model_, data, i, &row_))
              pair_contacts_.WriteRow(t, WithLoadFactor(row_), key);
        }
        if (settling_.path().size() > 0) {
          CalcSettlingRow(model_, data, !statics, kinetic, &row_);
          settling_.WriteRow(t, WithLoadFactor(row_), key);
        }
        last_row_time_ = t;
      }
      std::size_t batch = 0;
      for (std::size_t i = 0; i < num_tables_; ++i)
        batch = std::max(batch, tables_[i]->batch_bytes());
      if (batch >= kRowBatchBytes && !FlushRows(t)) return false;
    }
    if (frame && vtk_ &&
        !vtk_->WriteFrame(model_, data, statics ? load_factor_ : t, statics ? load_factor_ : 1.0))
      return WriteFailed(vtk_->dir() + "/frame files", t);
    return true;
  }

  // Ends the run as failed when it reaches outputs.max_rows (`what`: which output); false.
  bool LimitReached(const char* what, double t) {
    Finish("failed",
           "outputs.max_rows: the run reached " + std::to_string(outputs_.max_rows) + " " + what +
               " (the limit) at " + When(t, load_factor_) +
               "; record less often (outputs.interval, outputs.vtk_interval, outputs.rod_fields) "
               "or raise outputs.max_rows");
    return false;
  }

  // A row of a static analysis starts with the load factor (StaticColumns).
  const std::vector<double>& WithLoadFactor(const std::vector<double>& row) {
    if (scene_.analysis.kind != AnalysisKind::kStatic) return row;
    static_row_.assign(1, load_factor_);
    static_row_.insert(static_row_.end(), row.begin(), row.end());
    return static_row_;
  }

  // Writes the rows collected so far to the files, keeping the tables at the same row; on a
  // write error ends the run as failed.
  bool FlushRows(double t) {
    if (const CsvWriter* w = CsvWriter::FlushTogether(tables_.data(), num_tables_))
      return WriteFailed(w->path(), t);
    return true;
  }

  bool WriteFailed(const std::string& path, double t) {
    io_error_ = true;
    const int error = errno;
    Finish("failed",
           "cannot write at " + When(t, load_factor_) + ": " + path + ": " + std::strerror(error));
    return false;
  }

  // The contact law as resolved (only with contact, so that other runs' summaries keep their
  // text): its settings and the law of each pair of material groups, the scene's first
  // (groups null).
  void WriteContactLaws(JsonWriter& j) const {
    const ContactSettings& c = model_.contact;
    j.Key("contact").BeginObject();
    j.Field("friction_law", NameOf(c.friction_law)).Field("onset", c.onset);
    if (c.friction_law == FrictionLaw::kSmooth) j.Field("slip_velocity", c.slip_velocity);
    j.Key("materials").BeginArray();
    for (std::size_t i = 0; i < model_.contact_laws.size(); ++i) {
      const ContactMaterial& law = model_.contact_laws[i];
      j.BeginObject();
      if (i == 0) {
        j.Key("groups").Null();
      } else {
        j.Key("groups").BeginArray();
        for (int g : law.group)
          j.String(model_.contact_material_groups[static_cast<std::size_t>(g)].name);
        j.EndArray();
      }
      j.Field("friction", law.friction).Field("static_friction", law.static_friction);
      j.Field("stiffness", law.stiffness).Field("damping_ratio", law.damping_ratio);
      j.Field("tangential_stiffness", law.tangential_stiffness).Field("onset", law.onset);
      j.EndObject();
    }
    j.EndArray();
    j.EndObject();
  }

  // The summary of the run so far (run.h); false if it could not be written.
  bool WriteSummary() {
    last_summary_ = Clock::now();
    const AnalysisSettings& a = scene_.analysis;
    const DynamicOptions& d = a.dynamic;
    const StaticOptions& s = a.statics;
    const bool statics = a.kind == AnalysisKind::kStatic;
    const double wall = WallSeconds();
    const double simulated = statics ? 0.0 : data_.time - start_time_;
    JsonWriter j;
    j.BeginObject();
    j.Field("format", "screwfem run summary 1");
    j.Key("scene")
        .BeginObject()
        .Field("source", scene_.source)
        .Field("name", scene_.name)
        .EndObject();
    j.Field("status", status_).Field("message", message_);
    if (const char* name = SignalName(signal_))
      j.Field("signal", name);
    else
      j.Key("signal").Null();

    j.Key("settings").BeginObject();
    j.Field("analysis", NameOf(a.kind));
    // The threads the assembly ran on (analysis.threads resolved; assemble.h).
    j.Field("threads", data_.parallel.threads());
    if (!statics) {
      j.Field("start_time", start_time_).Field("end_time", a.end_time).Field("step", a.step);
      j.Field("align_steps", a.align_steps).Field("static_preload", a.static_preload);
      // rho_inf as the run used it (auto resolved: 0 with contact, docs/numerics.md).
      j.Field("rho_inf", ResolvedRhoInf(model_, d)).Field("max_iterations", d.max_iterations);
      if (HasContact(model_)) j.Field("line_search", d.line_search);  // (only with contact)
      if (a.stop_at_rest.enabled) {
        j.Key("stop_at_rest").BeginObject();
        j.Field("speed", a.stop_at_rest.speed);
        j.Field("angular_speed", a.stop_at_rest.angular_speed);
        j.Field("hold", a.stop_at_rest.hold);
        j.EndObject();
      } else {
        j.Field("stop_at_rest", false);
      }
      j.Field("max_halvings", d.max_halvings);
      j.Field("increment_tolerance", d.increment_tolerance);
      j.Field("constraint_tolerance", d.constraint_tolerance);
      j.Field("residual_tolerance", d.residual_tolerance);
      j.Field("use_tangent_operator", d.use_tangent_operator);
      j.Field("newton", NameOf(d.newton_matrix));
      j.Field("refresh_ratio", d.refresh_ratio);
      j.Field("predictor", NameOf(d.predictor));
      j.Field("convergence", NameOf(d.convergence));
      j.Field("restart_at_breakpoints", d.restart_at_breakpoints);
      j.Field("perturbed_start", d.perturbed_start);
      j.Field("constraints", NameOf(d.constraints));
      j.Field("adaptive_steps", a.adaptive_steps);
      if (a.adaptive_steps) {
        j.Field("absolute_tolerance", d.absolute_tolerance);
        j.Field("relative_tolerance", d.relative_tolerance);
        j.Field("min_step", d.min_step).Field("initial_step", d.initial_step);
        if (std::isfinite(d.max_step))
          j.Field("max_step", d.max_step);
        else
          j.Key("max_step").Null();
      }
    }
    if (statics || a.static_preload) {
      j.Key("statics").BeginObject();
      j.Field("time", statics ? s.time : a.start_time).Field("load_steps", s.load_steps);
      j.Field("method", NameOf(s.method)).Field("max_steps", s.max_steps);
      j.Field("start_load_factor", s.start_load_factor).Field("end_load_factor", s.end_load_factor);
      j.Field("max_halvings", s.max_halvings).Field("max_iterations", s.max_iterations);
      j.Field("residual_tolerance", s.residual_tolerance);
      j.Field("increment_tolerance", s.increment_tolerance);
      j.Field("constraint_tolerance", s.constraint_tolerance);
      j.EndObject();
    }
    j.Field("rod_inertia", NameOf(model_.rod_inertia));
    if (!model_.contact_pairs.empty() || !model_.contact_segments.empty()) WriteContactLaws(j);
    j.Key("gravity").BeginArray();
    for (int i = 0; i < 3; ++i) j.Number(model_.gravity(i));
    j.EndArray();
    j.Field("output_interval", outputs_.interval);
    j.Field("vtk", outputs_.vtk).Field("vtk_interval", outputs_.vtk_interval);
    j.Field("vtk_format", NameOf(outputs_.vtk_format));
    // (only when off, so that other runs' summaries keep their text)
    if (!outputs_.reactions) j.Field("reactions", false);
    if (!outputs_.energy) j.Field("energy", false);
    if (outputs_.rod_fields) {  // (only then, so that other runs' summaries keep their text)
      j.Field("rod_fields", true);
      if (FieldsApart())
        j.Field("rod_fields_interval", outputs_.rod_fields_interval);
      else
        j.Key("rod_fields_interval").Null();  // at the rows of points.csv
    }
    j.EndObject();

    long free_nodes = 0;
    for (const Node& n : model_.nodes) free_nodes += n.dof >= 0 ? 1 : 0;
    j.Key("counts").BeginObject();
    j.Field("nodes", static_cast<long>(model_.nodes.size())).Field("free_nodes", free_nodes);
    j.Field("rods", static_cast<long>(model_.rods.size()));
    j.Field("elements", static_cast<long>(model_.elements.size()));
    j.Field("conformed_nodes", static_cast<long>(model_.conformed_nodes));
    j.Field("rigid_bodies", static_cast<long>(model_.bodies.size()));
    j.Field("joints", static_cast<long>(model_.joints.size()));
    j.Field("point_loads", static_cast<long>(model_.point_loads.size()));
    j.Field("nv", model_.nv).Field("nc", model_.nc);
    j.Field("redundant_constraints", static_cast<long>(model_.redundant_rows.size()));
    j.Field("bandwidth", model_.bandwidth);
    j.EndObject();

    j.Key("outputs").BeginObject();
    j.Key("points").BeginArray();
    for (const OutputPoint& p : outputs_.points) j.String(p.name);
    j.EndArray();
    j.Key("joints").BeginArray();
    for (const OutputJoint& oj : outputs_.joints) j.String(oj.name);
    j.EndArray();
    if (outputs_.rod_fields) {  // the names of rod_fields.csv's rod indices
      j.Key("rods").BeginArray();
      for (const Rod& rod : model_.rods) j.String(rod.name);
      j.EndArray();
    }
    // The rows on disk (the summary is written after the tables are flushed).
    j.Field("rows", points_.rows()).Field("last_row_time", points_.last_time());
    j.Field("vtk_frames", vtk_ ? vtk_->frames() : 0);
    j.EndObject();

    j.Field("time", data_.time);
    // analysis.stop_at_rest: when the run ended at rest (null otherwise).
    if (!statics) {
      if (std::isnan(rest_time_))
        j.Key("rest_time").Null();
      else
        j.Field("rest_time", rest_time_);
    }
    j.Field("steps", integ_.steps);
    j.Field("newton_iterations", integ_.iterations);
    j.Field("max_iterations_per_step", integ_.max_iterations_in_step);
    j.Field("step_halvings", integ_.halvings);
    j.Field("matrix_factorizations", integ_.factorizations);
    // The direct solver of the Newton systems (docs/numerics.md, "Sparse direct solve").
    j.Key("linear_solver").BeginObject();
    j.Field("requested", NameOf(model_.linear_solver));
    j.Field("chosen", model_.sparse_solver ? "sparse" : "banded");
    j.Field("banded_flops", model_.banded_flops).Field("sparse_flops", model_.sparse_flops);
    // The costs auto compares (PredictedBandedCost, PredictedSparseCost; the sparse one null
    // when it was not analysed), and the contact coupling counted in the banded one.
    j.Field("coupled_nodes", model_.coupled_nodes).Field("coupling_flops", model_.coupling_flops);
    j.Field("banded_cost", PredictedBandedCost(model_));
    j.Field("sparse_cost", PredictedSparseCost(model_));
    j.Field("symbolic_analyses", static_cast<long>(data_.sparse.analyses()));
    // Patterns of contact couplings (SelectSparsePattern): changes of the pattern in use, and
    // those that took a kept pattern back without an analysis.
    j.Field("pattern_changes", static_cast<long>(data_.sparse.pattern_changes()));
    j.Field("pattern_cache_hits", static_cast<long>(data_.sparse.pattern_hits()));
    j.Field("factorizations", static_cast<long>(data_.sparse.factorizations()));
    j.Field("full_factorizations", static_cast<long>(data_.sparse.full_factorizations()));
    j.Field("refactorization_fallbacks", static_cast<long>(data_.sparse.fallbacks()));
    j.EndObject();
    j.Field("step_retries", integ_.retries);
    if (HasContact(model_)) j.Field("line_search_halvings", integ_.line_search_halvings);
    j.Field("estimated_convergences", integ_.estimated_convergences);
    j.Field("restarts", integ_.restarts);
    j.Field("perturbed_start_skips", integ_.perturbed_start_skips);
    // The step history: every accepted step (or substep of a halved one), and the attempts
    // the error control rejected.
    j.Key("step_history").BeginObject();
    j.Field("accepted", integ_.accepted_substeps).Field("rejected", integ_.rejected);
    if (integ_.accepted_substeps > 0) {
      j.Field("min_step", integ_.min_h).Field("max_step", integ_.max_h);
      j.Field("mean_step", integ_.sum_h / static_cast<double>(integ_.accepted_substeps));
    } else {
      j.Key("min_step").Null().Key("max_step").Null().Key("mean_step").Null();
    }
    j.EndObject();
    if (has_static_) {
      j.Key("static_solution").BeginObject();
      j.Field("converged", static_.converged).Field("load_factor", static_.load_factor);
      j.Field("load_steps", static_.load_steps)
          .Field("newton_iterations", static_.total_iterations);
      j.Field("halvings", static_.halvings).Field("limit_point", static_.limit_point);
      j.Key("limit_points").BeginArray();
      for (double lp : static_.limit_points) j.Number(lp);
      j.EndArray();
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
    return WriteFileAtomically(folder_, kSummaryFile, j.str());
  }

  const Scene& scene_;
  const OutputSpec outputs_;
  const Model& model_;
  const RunOptions& options_;
  OutputFolder folder_;  // the output directory, open (writers.h)
  Data& data_;
  Data dense_;  // step: auto: the state interpolated at output times inside a step
  Integrator& integ_;
  StaticResult static_;
  bool has_static_ = false;
  CsvWriter points_, joints_, reactions_, energy_, tendons_, forces_, actuators_;
  // Long format, a block of rows per output time (WriteRows), at the rows of points.csv or
  // (FieldsApart) at its own times.
  CsvWriter rod_fields_;
  std::vector<double> lead_;  // values after t on every rod_fields.csv row: the load factor
                              // in static analyses, none otherwise
  CsvWriter contacts_;        // long format (one row per active pair)
  CsvWriter pair_contacts_;   // the same for pairs of moving shapes (pair_contacts.csv)
  CsvWriter settling_;        // settling.csv (scenes with contact)
  // analysis.stop_at_rest (solve/rest.h): watched from Start; rest_time_ when it ended the run.
  RestCriterion stop_at_rest_;
  std::optional<RestWatch> rest_;
  double rest_time_ = NAN;
  // The open tables, flushed together (points and joints always), their
  // rows keyed by the output event (events_), so that a write error cuts every one of them
  // at the same output time.
  std::array<CsvWriter*, 11> tables_ = {&points_, &joints_, nullptr, nullptr, nullptr, nullptr,
                                        nullptr,  nullptr,  nullptr, nullptr, nullptr};
  std::size_t num_tables_ = 2;
  std::optional<VtkWriter> vtk_;
  std::optional<ProgressBar> progress_;
  std::vector<double> row_;
  std::vector<double> static_row_;            // load factor and row_ (static analyses)
  double load_factor_ = 0.0;                  // of the state recorded (static analyses)
  std::optional<OutputClock> rows_, frames_;  // dynamic analyses, from Start
  std::optional<OutputClock> fields_;         // ... with FieldsApart
  double start_time_;                         // of the recorded run [s]
  Clock::time_point wall_start_, last_summary_;
  double max_constraint_ = 0.0;
  double max_rotation_ = 0.0;   // largest relative rotation of one rod element so far [rad]
  double last_row_time_ = NAN;  // of the last row recorded (in the files once flushed)
  long long events_ = 0;        // output events recorded (the tables' row keys)
  long row_events_ = 0;         // ... with rows (outputs.max_rows)
  long field_events_ = 0;       // ... of rod_fields.csv at its own interval
  std::vector<double> event_load_factors_;  // static analyses: the load factor of each event
  std::string status_ = "running", message_;
  int signal_ = 0;         // the stop request's signal number
  bool io_error_ = false;  // the run failed writing its files
  OutputLock lock_;
  bool finished_ = false;
  StopRequest outer_stop_;  // StopWhenFinished's
};

Recording::Recording(const Scene& scene, const OutputSpec& outputs, const Model& model, Data& data,
                     Integrator& integrator, const std::string& outdir, const RunOptions& options)
    : impl_(std::make_unique<Impl>(scene, outputs, model, data, integrator, outdir, options)) {}

Recording::~Recording() {
  if (!impl_->finished()) impl_->Finish("failed", "the recording was not finished");
}

void Recording::StopAtRest(const RestCriterion& criterion) { impl_->StopAtRest(criterion); }
bool Recording::Start() { return impl_->Start(); }
bool Recording::started() const { return impl_->started(); }
void Recording::BeforeStep(double t_inputs) { impl_->BeforeStep(t_inputs); }
double Recording::NextOutputTime() const { return impl_->NextOutputTime(); }
bool Recording::OutputInsideStep(double t) { return impl_->OutputInsideStep(t); }
bool Recording::AfterStep(bool last) { return impl_->AfterStep(last); }
bool Recording::RecordStaticStep(double t, double load_factor) {
  return impl_->RecordStaticStep(t, load_factor);
}
void Recording::SetStaticResult(const StaticResult& result) { impl_->SetStaticResult(result); }
bool Recording::RecordStaticSolution(double t, bool row) {
  return impl_->RecordStaticSolution(t, row);
}
bool Recording::RecordFinalState() { return impl_->RecordFinalState(); }
StopRequest Recording::StopWhenFinished(const StopRequest& stop) {
  return impl_->StopWhenFinished(stop);
}
void Recording::Finish(const char* status, std::string message) {
  impl_->Finish(status, std::move(message));
}
void Recording::Interrupted(int signal, const std::string& when) {
  impl_->Interrupted(signal, when);
}
bool Recording::finished() const { return impl_->finished(); }
double Recording::last_row_time() const { return impl_->last_row_time(); }
RunResult Recording::Result() const { return impl_->Result(); }

}  // namespace screwfem
