// libFuzzer harness: the whole run path of `screwfem run SCENE -o OUTDIR [--inputs TABLE]`.
// ParseScene with overrides, ParseInputTable for a table carved from the same input
// (tests/fuzz/fuzz_input.h, SplitRunInput), then RunScene into a temporary output directory:
// static analyses and preloads, fixed and error-controlled (step: auto) steps, contact,
// tendons, run-time inputs, the recording of every table, summary.json and the ParaView
// frames. The run is cut to a few steps so that an input takes well under a second (RunCaps
// below). Failures as in fuzz_parse.cpp (an InputError of the table must name the table);
// RunScene may refuse settings with an InputError or end failed or interrupted (valid
// outcomes), but must never throw anything else, and a run that returns has written its
// summary.json and says why it stopped unless it completed.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <string>
#include <system_error>

#include <unistd.h>

#include "fuzz_input.h"
#include "screwfem/elements/contact.h"
#include "screwfem/io/input_table.h"
#include "screwfem/io/run.h"
#include "screwfem/io/scene.h"
#include "screwfem/model/errors.h"
#include "screwfem/solve/dynamics.h"

namespace {

constexpr const char* kTableSource = "fuzz_inputs.csv";

// The caps on one run. Each keeps the scene's own setting when that is smaller.
struct RunCaps {
  // Models: unknowns and unknowns x (half-bandwidth + 1), the size of the banded iteration
  // matrix in doubles over 3 (a 1000-element rod: 6000 unknowns, bandwidth 11). Larger models
  // stop after the build, as in fuzz_build.cpp. Once RunScene refuses a scene by its memory
  // estimate (--max-memory), set that limit in RunOptions instead and let large models reach
  // it; the cut of end_time below can likewise give way to a bound on the recorded rows
  // (outputs.max_rows), while max_polls keeps bounding the time (docs/fuzzing.md).
  int max_unknowns = 20000;
  double max_band_entries = 1e5;
  // Dynamic analyses: end_time cut to start_time + steps x the (first) step: 4 fixed steps,
  // 8 first steps of step: auto (its controller may take more, shorter ones).
  int fixed_steps = 4;
  int auto_steps = 8;
  int max_iterations = 20;  // Newton iterations per step or load step
  int max_halvings = 3;     // dynamic substeps 2..8; static: the first increment / 4
  // Statics and the preload: as fuzz_build.cpp.
  int load_steps = 3;
  int static_steps = 10;
  // Newton iterations and (sub)step attempts in all: RunScene's stop request (RunOptions::
  // stop, polled before each) ends the run as interrupted after these many polls, whatever
  // the controller or the halvings do; fewer for large models, whose iterations cost more
  // (at most max_unknown_polls unknowns x polls: a 1000-element rod, 6006 unknowns, has 33;
  // it took 0.7 CPU-s for 4 steps under the sanitizers).
  long max_polls = 120;
  double max_unknown_polls = 2e5;
  long min_polls = 8;
};

// With contact every Newton iteration may assemble up to 1 + kMaxLineSearchHalvings times (the
// contact line search, which the stop request does not poll): the budget per unknown shrinks
// by that much (the 20-rod pile example, 4920 unknowns, ran 14 s for 40 polls under the
// sanitizers before).
long PollBudgetFor(const screwfem::Model& m, const RunCaps& caps) {
  const double assemblies = screwfem::HasContact(m) ? 1.0 + screwfem::kMaxLineSearchHalvings : 1.0;
  const double by_size = caps.max_unknown_polls / (assemblies * std::max(1, m.num_unknowns()));
  return std::clamp(static_cast<long>(by_size), caps.min_polls, caps.max_polls);
}

bool TooLarge(const screwfem::Model& m, const RunCaps& caps) {
  // With contact a pattern analysis may come with every assembly (pairs that change), and the
  // line search assembles up to 7 times per iteration: such models count 7 times their size.
  const double n =
      m.num_unknowns() * (screwfem::HasContact(m) ? 1.0 + screwfem::kMaxLineSearchHalvings : 1.0);
  return n > caps.max_unknowns || n * (m.bandwidth + 1.0) > caps.max_band_entries;
}

void CapStatics(screwfem::StaticOptions& so, const RunCaps& caps) {
  so.load_steps = std::min(so.load_steps, caps.load_steps);
  so.max_halvings = std::min(so.max_halvings, caps.max_halvings);
  so.max_iterations = std::min(so.max_iterations, caps.max_iterations);
  so.max_steps = so.max_steps == 0 ? caps.static_steps : std::min(so.max_steps, caps.static_steps);
}

void CapAnalysis(screwfem::AnalysisSettings& a, const RunCaps& caps) {
  CapStatics(a.statics, caps);
  a.dynamic.max_iterations = std::min(a.dynamic.max_iterations, caps.max_iterations);
  a.dynamic.max_halvings = std::min(a.dynamic.max_halvings, caps.max_halvings);
  if (a.kind != screwfem::AnalysisKind::kDynamic) return;
  const int steps = a.adaptive_steps ? caps.auto_steps : caps.fixed_steps;
  // Only a valid grid is cut (RunScene refuses the others as they are); the cut one is
  // validated again by RunScene.
  if (std::isfinite(a.start_time) && std::isfinite(a.end_time) && a.step > 0.0 &&
      a.end_time - a.start_time > steps * a.step)
    a.end_time = a.start_time + steps * a.step;
}

struct PollBudget {
  long left = 0;
};

bool PollStop(void* context) {
  PollBudget* budget = static_cast<PollBudget*>(context);
  return --budget->left < 0;
}

// One output directory per process, emptied before every run and removed after it (libFuzzer
// ends a session with _Exit, so a destructor alone would leave the last run's files).
struct OutputDir {
  std::filesystem::path path;
  OutputDir() {
    path = std::filesystem::temp_directory_path() /
           ("screwfem-fuzz-run-" + std::to_string(static_cast<long>(getpid())));
  }
  ~OutputDir() { Remove(); }
  std::string Fresh() const {
    Remove();
    return path.string();
  }
  void Remove() const {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
};

// SCREWFEM_FUZZ_VERBOSE=1 (e.g. with the replay program): one line per input on stderr, what
// became of it.
bool Verbose() {
  static const bool verbose = std::getenv("SCREWFEM_FUZZ_VERBOSE") != nullptr;
  return verbose;
}

void Say(const char* what, const std::string& detail) {
  if (Verbose()) std::fprintf(stderr, "fuzz_run: %s: %s\n", what, detail.c_str());
}

[[noreturn]] void Fail(const char* what, const std::string& detail) {
  std::fprintf(stderr, "fuzz_run: %s: %s\n", what, detail.c_str());
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const OutputDir outdir;
  const RunCaps caps;
  const screwfem::fuzz::RunInput in = screwfem::fuzz::SplitRunInput(data, size);
  screwfem::Scene scene;
  try {
    scene = screwfem::ParseScene(in.scene.scene, screwfem::fuzz::kSource, in.scene.overrides);
  } catch (const screwfem::InputError& e) {
    if (std::string(e.what()).rfind(screwfem::fuzz::kSource, 0) != 0)
      Fail("scene error without the scene's name", e.what());
    Say("scene refused", e.what());
    return 0;
  }
  if (TooLarge(scene.model, caps)) {
    Say("model too large", std::to_string(scene.model.num_unknowns()) + " unknowns");
    return 0;
  }
  screwfem::RunOptions options;
  if (in.has_table) {
    try {
      options.inputs = screwfem::ParseInputTable(in.table, kTableSource, scene.model);
    } catch (const screwfem::InputError& e) {
      if (std::string(e.what()).rfind(kTableSource, 0) != 0)
        Fail("table error without the table's name", e.what());
      Say("table refused", e.what());
      return 0;
    }
  }
  CapAnalysis(scene.analysis, caps);
  PollBudget budget{PollBudgetFor(scene.model, caps)};
  options.stop.poll = PollStop;
  options.stop.context = &budget;
  const std::string dir = outdir.Fresh();
  screwfem::RunResult r;
  try {
    r = screwfem::RunScene(scene, dir, options);
  } catch (const screwfem::InputError& e) {
    outdir.Remove();
    if (std::string(e.what()).empty()) Fail("RunScene", "an InputError without a message");
    Say("run refused", e.what());
    return 0;
  } catch (const std::exception& e) {
    Fail("RunScene threw", e.what());
  }
  if (!std::filesystem::is_regular_file(std::filesystem::path(dir) / "summary.json"))
    Fail("RunScene", "returned without summary.json");
  if (!r.ok && r.message.empty()) Fail("RunScene", "stopped early without a message");
  outdir.Remove();
  Say(r.ok            ? "completed"
      : r.interrupted ? "interrupted"
                      : "failed",
      std::to_string(r.steps) + " steps, " + std::to_string(r.newton_iterations) +
          " Newton iterations, t = " + std::to_string(r.end_time) + " s" +
          (in.has_table ? ", inputs table" : "") + (r.ok ? "" : ": " + r.message));
  return 0;
}
