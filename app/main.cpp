// The screwfem command-line program (thin: parse arguments, call the library).
//
//   screwfem run SCENE.yaml -o OUTDIR [--set key=value]... [--quiet]
//   screwfem check SCENE.yaml [--set key=value]...
//   screwfem plot OUTDIR [OUTDIR...] -o FIGDIR [--points P8,P4] [--times 0,0.5,1] [--animate]
//   screwfem view OUTDIR [-o FILE.html]
//   screwfem --version
//
// Exit codes: 0 success, 1 a failed step or static solution, 2 invalid input or usage,
// 130 interrupted (SIGINT).
#include <CLI/CLI.hpp>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include "screwfem/io/run.h"
#include "screwfem/io/scene.h"
#include "screwfem/model/errors.h"

extern char** environ;

namespace {

constexpr int kExitFailed = 1;
constexpr int kExitInput = 2;
constexpr int kExitInterrupted = 130;
constexpr const char* kPython = "/usr/bin/python3";

std::atomic<bool> g_stop{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the SIGINT handler needs a lock-free flag");

extern "C" void OnSigint(int) { g_stop.store(true); }

// The first SIGINT asks the run to stop cleanly; a second one ends the program at once.
void InstallSigintHandler() {
  struct sigaction action {};
  action.sa_handler = OnSigint;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESETHAND;
  sigaction(SIGINT, &action, nullptr);
}

void PrintWarnings(const screwfem::Model& model) {
  for (const std::string& w : model.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
}

int Run(const std::string& scene_path, const std::string& outdir,
        const std::vector<std::string>& overrides, bool quiet) {
  try {
    const screwfem::Scene scene = screwfem::LoadScene(scene_path, overrides);
    PrintWarnings(scene.model);
    screwfem::RunOptions options;
    options.progress = !quiet && isatty(STDERR_FILENO);
    options.stop = &g_stop;
    InstallSigintHandler();
    const screwfem::RunResult r = screwfem::RunScene(scene, outdir, options);
    const char* status = r.ok ? "completed" : r.interrupted ? "interrupted" : "failed";
    std::printf("%s: t = %.6g s, %ld steps, %ld Newton iterations (at most %d per step), %ld halvings, "
                "%.3g s wall, max |phi| %.2g, max element rotation %.3g rad -> %s\n",
                status, r.end_time, r.steps, r.newton_iterations, r.max_iterations_per_step,
                r.halvings, r.wall_seconds, r.max_constraint_residual, r.max_element_rotation,
                outdir.c_str());
    if (!r.ok) std::fprintf(stderr, "%s\n", r.message.c_str());
    return r.ok ? 0 : r.interrupted ? kExitInterrupted : kExitFailed;
  } catch (const screwfem::InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return kExitInput;
  }
}

int Check(const std::string& scene_path, const std::vector<std::string>& overrides) {
  try {
    const screwfem::Scene scene = screwfem::LoadScene(scene_path, overrides);
    const screwfem::Model& m = scene.model;
    const screwfem::AnalysisSettings& a = scene.analysis;
    std::printf("%s: %s\n", scene.source.c_str(), scene.name.c_str());
    if (a.kind == screwfem::AnalysisKind::kStatic)
      std::printf("  analysis: static at t = %g s\n", a.statics.time);
    else
      std::printf("  analysis: dynamic from %g to %g s, step %g s, rho_inf %g%s\n", a.start_time,
                  a.end_time, a.step, a.dynamic.rho_inf, a.static_preload ? ", static preload" : "");
    std::printf("  %zu nodes, %zu rods (%zu elements), %zu rigid bodies, %zu joints, %zu loads\n",
                m.nodes.size(), m.rods.size(), m.elements.size(), m.bodies.size(), m.joints.size(),
                m.point_loads.size());
    std::printf("  unknowns: nv = %d, nc = %d (%zu redundant constraint rows), bandwidth %d\n", m.nv,
                m.nc, m.redundant_rows.size(), m.bandwidth);
    std::printf("  recorded: %zu points, %zu joints\n", scene.outputs.points.size(),
                scene.outputs.joints.size());
    for (const std::string& w : m.warnings) std::printf("  warning: %s\n", w.c_str());
    return 0;
  } catch (const screwfem::InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return kExitInput;
  }
}

// Runs a script of tools/ with Debian's python (full path, no PATH lookup): `script` unless the
// environment variable `env_var` names another file. Returns the script's exit status.
int RunPythonTool(const char* env_var, const std::string& script_default, const char* what,
                  const std::vector<std::string>& script_args) {
  const char* env_script = std::getenv(env_var);
  const std::string script = env_script && *env_script ? env_script : script_default;
  if (!std::filesystem::is_regular_file(script)) {
    std::fprintf(stderr, "error: %s script %s not found (set %s)\n", what, script.c_str(), env_var);
    return kExitInput;
  }
  if (access(kPython, X_OK) != 0) {
    std::fprintf(stderr, "error: %s not found (install python3-matplotlib and python3-numpy)\n",
                 kPython);
    return kExitInput;
  }
  std::vector<std::string> args = {kPython, script};
  args.insert(args.end(), script_args.begin(), script_args.end());
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int err = posix_spawn(&pid, kPython, nullptr, nullptr, argv.data(), environ);
  if (err != 0) {
    std::fprintf(stderr, "error: cannot start %s: %s\n", kPython, std::strerror(err));
    return kExitFailed;
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return kExitFailed;
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  return kExitFailed;
}

int Plot(const std::vector<std::string>& outdirs, const std::string& figdir,
         const std::string& points, const std::string& times, bool animate) {
  std::vector<std::string> args = outdirs;
  args.insert(args.end(), {"-o", figdir});
  if (!points.empty()) args.insert(args.end(), {"--points", points});
  if (!times.empty()) args.insert(args.end(), {"--times", times});
  if (animate) args.emplace_back("--animate");
  return RunPythonTool("SCREWFEM_PLOT_SCRIPT", SCREWFEM_PLOT_SCRIPT, "plotting", args);
}

int View(const std::string& outdir, const std::string& html) {
  std::vector<std::string> args = {outdir};
  if (!html.empty()) args.insert(args.end(), {"-o", html});
  return RunPythonTool("SCREWFEM_VIEW_SCRIPT", SCREWFEM_VIEW_SCRIPT, "viewer", args);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"screwfem: geometrically exact screw-based FEM for articulated soft robots"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("screwfem ") + SCREWFEM_VERSION);

  std::string scene_path, outdir, figdir, points, times, html;
  std::vector<std::string> overrides, outdirs;
  bool quiet = false, animate = false;
  const auto add_overrides = [&](CLI::App* cmd) {
    cmd->add_option("--set", overrides, "override a scene value, e.g. analysis.step=5e-4 (repeatable)")
        ->type_name("KEY=VALUE")
        ->allow_extra_args(false);
  };

  CLI::App* run = app.add_subcommand("run", "run a scene and write its results");
  run->add_option("scene", scene_path, "scene file (YAML)")->required();
  run->add_option("-o,--output", outdir, "output directory (created if needed)")->required();
  add_overrides(run);
  run->add_flag("-q,--quiet", quiet, "no progress bar");

  CLI::App* check = app.add_subcommand("check", "validate a scene and print its size");
  check->add_option("scene", scene_path, "scene file (YAML)")->required();
  add_overrides(check);

  CLI::App* plot = app.add_subcommand("plot", "plot results of one or more runs (matplotlib)");
  plot->add_option("outdirs", outdirs, "run output directories")->required();
  plot->add_option("-o,--output", figdir, "figure directory (created if needed)")->required();
  plot->add_option("--points", points, "comma-separated point names (default: all)");
  plot->add_option("--times", times, "comma-separated snapshot times [s] (default: 5 evenly spaced)");
  plot->add_flag("--animate", animate,
                 "also write animation_RUN.gif per run (and .mp4 when ffmpeg is installed)");

  CLI::App* view = app.add_subcommand("view", "write a self-contained HTML viewer of a run (three.js)");
  view->add_option("outdir", outdir, "run output directory")->required();
  view->add_option("-o,--output", html, "HTML file to write (default: OUTDIR/view.html)");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : kExitInput;
  }
  if (run->parsed()) return Run(scene_path, outdir, overrides, quiet);
  if (check->parsed()) return Check(scene_path, overrides);
  if (view->parsed()) return View(outdir, html);
  return Plot(outdirs, figdir, points, times, animate);
}
