// The screwfem command-line program (thin: parse arguments, call the library).
//
//   screwfem run SCENE.yaml -o OUTDIR [--set key=value]... [--quiet] [--force]
//                [--inputs TABLE.csv] [--max-memory SIZE]
//   screwfem check SCENE.yaml [--set key=value]... [--max-memory SIZE]
//   screwfem inverse SCENE.yaml --targets TARGETS.yaml -o OUTDIR [--set key=value]...
//   screwfem plot OUTDIR [OUTDIR...] -o FIGDIR [--points P8,P4] [--times 0,0.5,1]
//                 [--animate [--fps 25] [--speed 1]]
//   screwfem view OUTDIR [-o FILE.html]
//   screwfem sweep SCENE.yaml --grid key=v1,v2 [--grid ...] -o DIR [--resume] [...]
//   screwfem --version
//
// `plot`, `view` and `sweep` run Python (Debian's /usr/bin/python3): tools/screwfem_plot.py,
// tools/screwfem_view.py, and `python3 -m screwfem sweep` with the package of the build tree
// (python/screwfem).
//
// Exit codes: 0 success, 1 a failed step or static solution, 2 invalid input or usage, or
// an output directory that cannot be used or written (in use, earlier results, a full disk),
// 3 an internal error (any exception the program did not expect, e.g. out of memory),
// 128 + the signal number when a signal stopped the run: 130 SIGINT, 143 SIGTERM, 129 SIGHUP.
#include <CLI/CLI.hpp>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <new>
#include <string>
#include <vector>

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include "screwfem/io/inverse_file.h"
#include "screwfem/io/run.h"
#include "screwfem/io/scene.h"
#include "screwfem/model/errors.h"
#include "screwfem/model/memory.h"

extern char** environ;

namespace {

constexpr int kExitFailed = 1;
constexpr int kExitInput = 2;
constexpr int kExitInterrupted = 130;
constexpr const char* kPython = "/usr/bin/python3";

constexpr int kExitInternal = 3;

// The number of the first signal that asked the run to stop (0: none).
std::atomic<int> g_stop{0};
static_assert(std::atomic<int>::is_always_lock_free, "the signal handler needs a lock-free flag");

extern "C" void OnStopSignal(int signal) { g_stop.store(signal); }

// SIGINT, SIGTERM and SIGHUP ask the run to stop cleanly (files flushed, summary saying which
// signal); a second one of the same kind ends the program at once.
void InstallStopHandlers() {
  struct sigaction action {};
  action.sa_handler = OnStopSignal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESETHAND;
  for (int signal : {SIGINT, SIGTERM, SIGHUP}) sigaction(signal, &action, nullptr);
}

void PrintWarnings(const screwfem::Model& model) {
  for (const std::string& w : model.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
}

// An InputError while reading or building after a stop signal: the signal's exit code.
int InputErrorExit(const screwfem::InputError& e) {
  const int signal = g_stop.load();
  if (signal != 0) {
    std::fprintf(stderr, "interrupted: %s\n", e.what());
    return 128 + signal;
  }
  std::fprintf(stderr, "error: %s\n", e.what());
  return kExitInput;
}

// --max-memory SIZE: the process default of the memory limit (model/memory.h).
void SetMaxMemory(const std::string& size) {
  if (!size.empty())
    screwfem::SetDefaultMemoryLimit(screwfem::ParseMemorySize(size, "--max-memory"));
}

int Run(const std::string& scene_path, const std::string& outdir,
        const std::vector<std::string>& overrides, const std::string& inputs, bool quiet,
        bool force, const std::string& max_memory) {
  try {
    SetMaxMemory(max_memory);
    screwfem::StopRequest stop;
    stop.flag = &g_stop;
    const screwfem::Scene scene = screwfem::LoadScene(scene_path, overrides, stop);
    PrintWarnings(scene.model);
    screwfem::RunOptions options;
    options.progress = !quiet && isatty(STDERR_FILENO);
    options.stop = stop;
    options.replace_results = force;
    // A file size limit (ulimit -f) makes a write fail with EFBIG rather than kill the
    // program: the run then ends as failed, its files cut at a complete row, the summary
    // saying why (Python ignores SIGXFSZ as well).
    std::signal(SIGXFSZ, SIG_IGN);
    if (!inputs.empty()) options.inputs = screwfem::ReadInputTable(inputs, scene.model, stop);
    const screwfem::RunResult r = screwfem::RunScene(scene, outdir, options);
    const bool statics = scene.analysis.kind == screwfem::AnalysisKind::kStatic;
    const char* status = r.ok                                        ? "completed"
                         : !r.interrupted                            ? "failed"
                         : r.signal == SIGTERM || r.signal == SIGHUP ? "terminated"
                                                                     : "interrupted";
    // Static analyses: where the load path got to (every state has the same t).
    char where[64];
    if (statics)
      std::snprintf(where, sizeof where, "load factor λ = %.6g, %ld load steps", r.load_factor,
                    r.steps);
    else
      std::snprintf(where, sizeof where, "t = %.6g s, %ld steps", r.end_time, r.steps);
    std::printf(
        "%s: %s, %ld Newton iterations (at most %d per step), %ld halvings, %.3g s wall, "
        "max |phi| %.2g, max element rotation %.3g rad -> %s\n",
        status, where, r.newton_iterations, r.max_iterations_per_step, r.halvings, r.wall_seconds,
        r.max_constraint_residual, r.max_element_rotation, outdir.c_str());
    if (!r.ok) std::fprintf(stderr, "%s\n", r.message.c_str());
    if (r.ok) return 0;
    if (r.interrupted) return r.signal > 0 ? 128 + r.signal : kExitInterrupted;
    return r.io_error ? kExitInput : kExitFailed;
  } catch (const screwfem::InputError& e) {
    return InputErrorExit(e);
  }
}

int Check(const std::string& scene_path, const std::vector<std::string>& overrides,
          const std::string& max_memory) {
  try {
    SetMaxMemory(max_memory);
    const screwfem::Scene scene = screwfem::LoadScene(scene_path, overrides);
    const screwfem::Model& m = scene.model;
    const screwfem::AnalysisSettings& a = scene.analysis;
    std::printf("%s: %s\n", scene.source.c_str(), scene.name.c_str());
    if (a.kind == screwfem::AnalysisKind::kStatic)
      std::printf(
          "  analysis: static, load factor λ from %g to %g in %d load steps (loads at "
          "t = %g s)\n",
          a.statics.start_load_factor, a.statics.end_load_factor, a.statics.load_steps,
          a.statics.time);
    else
      std::printf("  analysis: dynamic from %g to %g s, step %g s, rho_inf %g%s%s\n", a.start_time,
                  a.end_time, a.step, screwfem::ResolvedRhoInf(m, a.dynamic),
                  a.dynamic.rho_inf < 0.0 ? " (auto)" : "",
                  a.static_preload ? ", static preload" : "");
    std::printf("  %zu nodes, %zu rods (%zu elements), %zu rigid bodies, %zu joints, %zu loads\n",
                m.nodes.size(), m.rods.size(), m.elements.size(), m.bodies.size(), m.joints.size(),
                m.point_loads.size());
    std::printf("  unknowns: nv = %d, nc = %d (%zu redundant constraint rows), bandwidth %d\n",
                m.nv, m.nc, m.redundant_rows.size(), m.bandwidth);
    std::printf("  recorded: %zu points, %zu joints\n", scene.outputs.points.size(),
                scene.outputs.joints.size());
    // The memory of the run, part by part (model/memory.h, EstimateRunMemory).
    screwfem::IntegratorMemoryOptions mo;
    mo.statics = a.kind == screwfem::AnalysisKind::kStatic;
    mo.adaptive = a.adaptive_steps;
    mo.perturbed_start = a.dynamic.perturbed_start;
    mo.ggl = a.dynamic.constraints == screwfem::ConstraintFormulation::kGgl;
    const std::vector<screwfem::MemoryPart> parts = screwfem::EstimateRunMemory(m, mo);
    std::printf(
        "  memory: about %s for the model and the solver's workspace (limit %s)\n",
        screwfem::FormatBytes(screwfem::TotalBytes(parts)).c_str(),
        screwfem::FormatBytes(static_cast<double>(screwfem::ResolveMemoryLimit(m.memory_limit)))
            .c_str());
    for (const screwfem::MemoryPart& p : parts)
      std::printf("    %s: %s\n", p.part.c_str(), screwfem::FormatBytes(p.bytes).c_str());
    // The output times the run will record, against outputs.max_rows (refused above it).
    const screwfem::OutputEstimate e = screwfem::EstimateOutputs(scene, scene.outputs);
    const auto count = [](double n) {
      return std::isnan(n) ? std::string("(not known ahead: step auto, interval 0)")
                           : std::to_string(static_cast<long long>(n));
    };
    std::printf("  outputs: about %s rows per table, %s ParaView frames", count(e.rows).c_str(),
                count(e.frames).c_str());
    if (e.field_times > 0.0) std::printf(", %s rod_fields.csv times", count(e.field_times).c_str());
    std::printf(" (outputs.max_rows %ld)\n", scene.outputs.max_rows);
    screwfem::CheckOutputRows(scene, scene.outputs);
    for (const std::string& w : m.warnings) std::printf("  warning: %s\n", w.c_str());
    return 0;
  } catch (const screwfem::InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return kExitInput;
  }
}

// Inverse statics of a targets file (io/inverse_file.h): 0 when every target was reached, 1
// when one was not (reported with its nearest equilibrium), 2 for invalid input.
int Inverse(const std::string& scene_path, const std::string& targets_path,
            const std::string& outdir, const std::vector<std::string>& overrides) {
  try {
    const screwfem::Scene scene = screwfem::LoadScene(scene_path, overrides);
    PrintWarnings(scene.model);
    const screwfem::InverseFile file = screwfem::LoadInverseFile(targets_path, scene);
    const screwfem::InverseRunResult r = screwfem::RunInverseFile(scene, file, outdir);
    std::printf("inverse: %d of %zu targets reached, %d not -> %s/inverse.csv\n", r.reached,
                file.solves.size(), r.unreachable, outdir.c_str());
    if (r.unreachable > 0) std::fprintf(stderr, "%s", r.message.c_str());
    return r.unreachable > 0 ? kExitFailed : 0;
  } catch (const screwfem::InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return kExitInput;
  }
}

// The directory above the one this program is in: the build directory in a build tree, the
// prefix in an installation (cmake/ScrewfemInstall.cmake).
std::filesystem::path ProgramPrefix() {
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::filesystem::path() : exe.parent_path().parent_path();
}

// A tool script of screwfem: $env_var when set, otherwise <prefix>/share/screwfem/<name>,
// where the build tree and an installation both put them.
std::string ToolScript(const char* env_var, const char* name) {
  const char* env = std::getenv(env_var);
  if (env && *env) return env;
  return (ProgramPrefix() / "share" / "screwfem" / name).string();
}

// The directory holding the Python package screwfem: $SCREWFEM_PYTHONPATH when set, otherwise
// <prefix>/python in a build tree or <prefix>/share/screwfem/python in an installation.
std::string PythonPackageDir() {
  const char* env = std::getenv("SCREWFEM_PYTHONPATH");
  if (env && *env) return env;
  const std::filesystem::path build_tree = ProgramPrefix() / "python";
  if (std::filesystem::is_regular_file(build_tree / "screwfem" / "__init__.py"))
    return build_tree.string();
  return (ProgramPrefix() / "share" / "screwfem" / "python").string();
}

// Runs Debian's python (full path, no PATH lookup) with `args` after the interpreter, and with
// `python_path` first on PYTHONPATH when it is not empty; returns its exit code (128 + signal
// when killed). While it runs, SIGINT (Ctrl-C reaches the whole foreground process group) is
// left to the child: this process waits for it to exit.
int RunPython(std::vector<std::string> args, const std::string& python_path) {
  if (access(kPython, X_OK) != 0) {
    std::fprintf(stderr, "error: %s not found (install python3 and the packages in the README)\n",
                 kPython);
    return kExitInput;
  }
  args.insert(args.begin(), kPython);
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::vector<std::string> env_strings;
  for (char** e = environ; *e != nullptr; ++e)
    if (python_path.empty() || std::strncmp(*e, "PYTHONPATH=", 11) != 0)
      env_strings.emplace_back(*e);
  if (!python_path.empty()) {
    const char* old = std::getenv("PYTHONPATH");
    const std::string rest = old && *old ? std::string(":") + old : "";
    env_strings.push_back("PYTHONPATH=" + python_path + rest);
  }
  std::vector<char*> envp;
  for (std::string& e : env_strings) envp.push_back(e.data());
  envp.push_back(nullptr);
  // A handler (not SIG_IGN) so that the child starts with the default disposition; Ctrl-C
  // is the child's to act on, this process waits for it.
  struct sigaction action {};
  action.sa_handler = OnStopSignal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  pid_t pid = 0;
  const int err = posix_spawn(&pid, kPython, nullptr, nullptr, argv.data(), envp.data());
  if (err != 0) {
    std::fprintf(stderr, "error: cannot start %s: %s\n", kPython, std::strerror(err));
    return kExitFailed;
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return kExitFailed;
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return kExitFailed;
}

// Runs a script of screwfem's tools with Debian's python (ToolScript: `env_var` overrides its
// location). Returns the script's exit status.
int RunPythonTool(const char* env_var, const char* name, const char* what,
                  const std::vector<std::string>& script_args) {
  const std::string script = ToolScript(env_var, name);
  if (!std::filesystem::is_regular_file(script)) {
    std::fprintf(stderr, "error: %s script %s not found (set %s)\n", what, script.c_str(), env_var);
    return kExitInput;
  }
  std::vector<std::string> args = {script};
  args.insert(args.end(), script_args.begin(), script_args.end());
  return RunPython(args, "");
}

// fps and speed go to the script as given (it checks them).
int Plot(const std::vector<std::string>& outdirs, const std::string& figdir,
         const std::string& points, const std::string& times, bool animate, const std::string& fps,
         const std::string& speed) {
  std::vector<std::string> args = outdirs;
  args.insert(args.end(), {"-o", figdir});
  if (!points.empty()) args.insert(args.end(), {"--points", points});
  if (!times.empty()) args.insert(args.end(), {"--times", times});
  if (animate) args.emplace_back("--animate");
  if (!fps.empty()) args.insert(args.end(), {"--fps", fps});
  if (!speed.empty()) args.insert(args.end(), {"--speed", speed});
  return RunPythonTool("SCREWFEM_PLOT_SCRIPT", "screwfem_plot.py", "plotting", args);
}

int View(const std::string& outdir, const std::string& html) {
  std::vector<std::string> args = {outdir};
  if (!html.empty()) args.insert(args.end(), {"-o", html});
  return RunPythonTool("SCREWFEM_VIEW_SCRIPT", "screwfem_view.py", "viewer", args);
}

// Runs `python3 -m screwfem sweep ARGS...` with the package of PythonPackageDir (it must hold
// screwfem/__init__.py).
int Sweep(const std::vector<std::string>& sweep_args) {
  const std::string dir = PythonPackageDir();
  if (!std::filesystem::is_regular_file(std::filesystem::path(dir) / "screwfem" / "__init__.py")) {
    std::fprintf(stderr,
                 "error: Python package screwfem not found in %s (build the target _screwfem, or "
                 "set SCREWFEM_PYTHONPATH)\n",
                 dir.c_str());
    return kExitInput;
  }
  std::vector<std::string> args = {"-m", "screwfem", "sweep"};
  args.insert(args.end(), sweep_args.begin(), sweep_args.end());
  return RunPython(args, dir);
}

int Main(int argc, char** argv) {
  CLI::App app{"screwfem: geometrically exact screw-based FEM for articulated soft robots"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("screwfem ") + SCREWFEM_VERSION);

  std::string scene_path, outdir, figdir, points, times, html, inputs, fps, speed, max_memory,
      threads;
  std::vector<std::string> overrides, outdirs;
  bool quiet = false, force = false, animate = false;
  const auto add_overrides = [&](CLI::App* cmd) {
    cmd->add_option("--set", overrides,
                    "override a scene value, e.g. analysis.step=5e-4 (repeatable)")
        ->type_name("KEY=VALUE")
        ->allow_extra_args(false);
  };
  const auto add_max_memory = [&](CLI::App* cmd) {
    cmd->add_option("--max-memory", max_memory,
                    "refuse a scene whose model and solver would need more memory than SIZE "
                    "(e.g. 8G, 512M; default: half the physical memory; docs/limits.md)")
        ->type_name("SIZE");
  };

  CLI::App* run = app.add_subcommand("run", "run a scene and write its results");
  run->add_option("scene", scene_path, "scene file (YAML)")->required();
  run->add_option("-o,--output", outdir, "output directory (created if needed)")->required();
  add_overrides(run);
  run->add_option("--inputs", inputs,
                  "CSV table of run-time input values: header t,NAME,..., one row per time "
                  "(linear between rows, held outside; docs/scene-format.md)")
      ->type_name("TABLE.csv");
  add_max_memory(run);
  run->add_option("--threads", threads,
                  "threads of the assembly: auto or N >= 1 (same as --set analysis.threads=N; "
                  "docs/scene-format.md)")
      ->type_name("N");
  run->add_flag("-q,--quiet", quiet, "no progress bar");
  run->add_flag("-f,--force", force,
                "replace the results of an earlier run in OUTDIR (removes screwfem's files only)");

  CLI::App* check = app.add_subcommand("check", "validate a scene and print its size");
  check->add_option("scene", scene_path, "scene file (YAML)")->required();
  add_overrides(check);
  add_max_memory(check);

  std::string targets_path;
  CLI::App* inverse = app.add_subcommand(
      "inverse", "inverse statics: the actuator inputs that put scene points on targets");
  inverse->add_option("scene", scene_path, "scene file (YAML)")->required();
  inverse
      ->add_option("--targets", targets_path,
                   "targets file (YAML: parameters with bounds, targets per point; "
                   "docs/scene-format.md)")
      ->required();
  inverse->add_option("-o,--output", outdir, "output directory (created if needed)")->required();
  add_overrides(inverse);

  CLI::App* plot = app.add_subcommand("plot", "plot results of one or more runs (matplotlib)");
  plot->add_option("outdirs", outdirs, "run output directories")->required();
  plot->add_option("-o,--output", figdir, "figure directory (created if needed)")->required();
  plot->add_option("--points", points, "comma-separated point names (default: all)");
  plot->add_option("--times", times,
                   "comma-separated times [s] of the snapshots and rod fields (default: 5 "
                   "evenly spaced)");
  plot->add_flag("--animate", animate,
                 "also write animation_RUN.gif per run (and .mp4 when ffmpeg is installed)");
  plot->add_option("--fps", fps, "frames per second of the animation (default 25, at most 50)")
      ->type_name("N");
  plot->add_option("--speed", speed,
                   "simulated seconds per second of the animation (default 1: real time)")
      ->type_name("X");

  CLI::App* view =
      app.add_subcommand("view", "write a self-contained HTML viewer of a run (three.js)");
  view->add_option("outdir", outdir, "run output directory")->required();
  view->add_option("-o,--output", html, "HTML file to write (default: OUTDIR/view.html)");

  // Everything after `sweep` goes to the Python front end (python/screwfem/__main__.py), which
  // parses and documents it (`screwfem sweep --help`).
  CLI::App* sweep = app.add_subcommand(
      "sweep", "run many variants of a scene on a Dask cluster (python3 -m screwfem sweep)");
  sweep->prefix_command();
  sweep->set_help_flag();

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : kExitInput;
  }
  if (run->parsed()) {
    InstallStopHandlers();
    // --threads N is the last override, so it wins over a --set of the same key.
    if (!threads.empty()) overrides.push_back("analysis.threads=" + threads);
    return Run(scene_path, outdir, overrides, inputs, quiet, force, max_memory);
  }
  if (check->parsed()) return Check(scene_path, overrides, max_memory);
  if (inverse->parsed()) return Inverse(scene_path, targets_path, outdir, overrides);
  if (sweep->parsed()) return Sweep(sweep->remaining());
  if (view->parsed()) return View(outdir, html);
  return Plot(outdirs, figdir, points, times, animate, fps, speed);
}

}  // namespace

// Every exception ends the program with a message and exit code 3, never an abort.
int main(int argc, char** argv) {
  try {
    return Main(argc, argv);
  } catch (const std::bad_alloc&) {
    std::fputs("internal error: out of memory\n", stderr);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "internal error: %s\n", e.what());
  } catch (...) {
    std::fputs("internal error: an unknown exception\n", stderr);
  }
  return kExitInternal;
}
