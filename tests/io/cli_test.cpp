// The screwfem program (app/main.cpp), run as a child process on tests/data/pendulum.yaml:
// files and exit codes of run (0 completed, 1 failed step, 2 input error, 130 SIGINT),
// check, plot and view (which run tools/screwfem_plot.py and tools/screwfem_view.py with
// /usr/bin/python3), --version, and sweep's package lookup.
#include <gtest/gtest.h>
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "run_test_util.h"

extern char** environ;

namespace screwfem::cli_test {
namespace {

using test::ParseJsonFile;
using test::ReadCsv;
using test::ReadFile;
using test::ScopedDir;
using test::Table;

#ifdef SCREWFEM_CLI_PATH
constexpr const char* kCli = SCREWFEM_CLI_PATH;
#else
constexpr const char* kCli = nullptr;
#endif
const std::string kPendulum = std::string(SCREWFEM_TEST_DATA_DIR) + "/pendulum.yaml";

struct Outcome {
  int code = -1;  // exit status, or 128 + signal
  std::string out, err;
};

// Starts `program args...` with stdout and stderr captured in files under `dir`.
pid_t Spawn(const std::string& program, const std::vector<std::string>& args,
            const std::string& dir, const std::vector<std::string>& extra_env = {}) {
  std::vector<std::string> argv_text = {program};
  argv_text.insert(argv_text.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : argv_text) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::vector<std::string> env_text(extra_env);
  for (char** e = environ; *e; ++e) env_text.emplace_back(*e);
  std::vector<char*> envp;
  for (std::string& e : env_text) envp.push_back(e.data());
  envp.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  const std::string out = dir + "/stdout.txt", err = dir + "/stderr.txt";
  posix_spawn_file_actions_addopen(&actions, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&actions, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, program.c_str(), &actions, nullptr, argv.data(), envp.data());
  posix_spawn_file_actions_destroy(&actions);
  EXPECT_EQ(rc, 0) << "cannot start " << program;
  return rc == 0 ? pid : -1;
}

Outcome Wait(pid_t pid, const std::string& dir) {
  Outcome o;
  int status = 0;
  if (pid > 0 && waitpid(pid, &status, 0) == pid)
    o.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  o.out = ReadFile(dir + "/stdout.txt");
  o.err = ReadFile(dir + "/stderr.txt");
  return o;
}

Outcome RunCli(const std::vector<std::string>& args, const std::string& dir,
               const std::vector<std::string>& env = {}) {
  std::filesystem::create_directories(dir);
  return Wait(Spawn(kCli, args, dir, env), dir);
}

#define REQUIRE_CLI()                                                                           \
  do {                                                                                          \
    if (kCli == nullptr) GTEST_SKIP() << "the build did not say where the screwfem program is"; \
  } while (0)

TEST(Cli, RunWritesResultsAndExitsZero) {
  REQUIRE_CLI();
  const ScopedDir tmp("cli_run");
  const std::string out = tmp.path() + "/out";
  const Outcome o = RunCli({"run", kPendulum, "-o", out, "--quiet"}, tmp.path());
  ASSERT_EQ(o.code, 0) << o.err;
  EXPECT_EQ(o.out.rfind("completed: t = 0.5 s, 500 steps", 0), 0u) << o.out;
  EXPECT_EQ(o.err, "");  // no progress bar (quiet, and stderr is not a terminal)
  const Table points = ReadCsv(out + "/points.csv");
  ASSERT_TRUE(points.well_formed) << points.problem;
  EXPECT_EQ(points.rows.size(), 51u);
  EXPECT_EQ(points.columns[1], "tip.x");
  const Table joints = ReadCsv(out + "/joints.csv");
  EXPECT_EQ(joints.columns[1], "hinge.q");
  const auto summary = ParseJsonFile(out + "/summary.json");
  ASSERT_TRUE(summary);
  EXPECT_EQ(summary->Find("status")->string, "completed");
  EXPECT_EQ(summary->Find("scene.source")->string, kPendulum);
  EXPECT_TRUE(std::filesystem::is_regular_file(out + "/vtk/motion.pvd"));
}

TEST(Cli, RunDescribesTheJointCoordinatesInJointsJson) {
  REQUIRE_CLI();
  const ScopedDir tmp("cli_joints_json");
  const std::string out = tmp.path() + "/out";
  ASSERT_EQ(
      RunCli({"run", kPendulum, "-o", out, "-q", "--set", "analysis.end_time=0.01"}, tmp.path())
          .code,
      0);
  const auto joints = ParseJsonFile(out + "/joints.json");
  ASSERT_TRUE(joints);
  EXPECT_EQ(joints->Find("format")->string, "screwfem joints 1");
  const test::Json& list = *joints->Find("joints");
  ASSERT_EQ(list.array.size(), 1u);
  const test::Json& hinge = list.array[0];
  EXPECT_EQ(hinge.Find("name")->string, "hinge");
  EXPECT_EQ(hinge.Find("type")->string, "revolute");
  EXPECT_EQ(hinge.Find("drive")->string, "none");
  EXPECT_EQ(hinge.Find("column")->string, "hinge");
  ASSERT_EQ(hinge.Find("coordinates")->array.size(), 1u);
  const test::Json& q = hinge.Find("coordinates")->array[0];
  EXPECT_EQ(q.Find("column")->string, "hinge");  // joints.csv: hinge.q, hinge.qd, ...
  EXPECT_EQ(q.Find("quantity")->string, "angle");
  EXPECT_EQ(q.Find("unit")->string, "rad");
  EXPECT_EQ(q.Find("effort_unit")->string, "N m");
}

TEST(Cli, OverridesApplyInOrder) {
  REQUIRE_CLI();
  const ScopedDir tmp("cli_set");
  const std::string out = tmp.path() + "/out";
  const Outcome o = RunCli({"run", kPendulum, "--set", "analysis.end_time=0.1", "-o", out, "--set",
                            "analysis.step=2e-3", "--set", "outputs.interval=0.05"},
                           tmp.path());
  ASSERT_EQ(o.code, 0) << o.err;
  EXPECT_NE(o.out.find("50 steps"), std::string::npos) << o.out;
  EXPECT_EQ(ReadCsv(out + "/points.csv").rows.size(), 3u);  // t = 0, 0.05, 0.1
}

// --threads N is analysis.threads=N after every --set: summary.json reports it; a bad value
// is an input error naming the key.
TEST(Cli, ThreadsFlagSetsTheAssemblyThreads) {
  REQUIRE_CLI();
  const ScopedDir tmp("cli_threads");
  const std::string out = tmp.path() + "/out";
  Outcome o = RunCli({"run", kPendulum, "-o", out, "-q", "--threads", "2", "--set",
                      "analysis.threads=1", "--set", "analysis.end_time=0.01"},
                     tmp.path());
  ASSERT_EQ(o.code, 0) << o.err;
  EXPECT_NE(ReadFile(out + "/summary.json").find("\"threads\": 2,"), std::string::npos);
  o = RunCli({"run", kPendulum, "-o", tmp.path() + "/bad", "--threads", "0"}, tmp.path());
  EXPECT_EQ(o.code, 2);
  EXPECT_NE(o.err.find("analysis.threads: expected 'auto' or an integer from 1 to 256, got '0'"),
            std::string::npos)
      << o.err;
}

TEST(Cli, InputErrorsExitTwoWithAPrefixedMessage) {
  REQUIRE_CLI();
  const ScopedDir tmp("cli_input");
  Outcome o = RunCli({"run", kPendulum, "-o", tmp.path() + "/out", "--set", "analysis.step=abc"},
                     tmp.path());
  EXPECT_EQ(o.code, 2);
  EXPECT_EQ(o.err.rfind("error: ", 0), 0u) << o.err;
  EXPECT_NE(o.err.find("analysis.step"), std::string::npos) << o.err;
  o = RunCli({"run", tmp.path() + "/missing.yaml", "-o", tmp.path() + "/out"}, tmp.path());
  EXPECT_EQ(o.code, 2);
  EXPECT_EQ(o.err.rfind("error: ", 0), 0u) << o.err;
  o = RunCli({"check", kPendulum, "--set", "analysis.step=-1"}, tmp.path());
  EXPECT_EQ(o.code, 2);
  EXPECT_EQ(o.err.rfind("error: ", 0), 0u) << o.err;
  // Usage errors: no subcommand, a missing -o.
  EXPECT_EQ(RunCli({}, tmp.path()).code, 2);
  EXPECT_EQ(RunCli({"run", kPendulum}, tmp.path()).code, 2);
}

TEST(Cli, FailedStepExitsOneAndSaysWhen) {
  REQUIRE_CLI();
  const ScopedDir tmp("cli_failed");
  const std::string out = tmp.path() + "/out";
  const Outcome o = RunCli({"run", kPendulum, "-o", out, "--set", "analysis.max_iterations=1",
                            "--set", "analysis.predictor=zero", "--set", "analysis.max_halvings=1"},
                           tmp.path());
  EXPECT_EQ(o.code, 1);
  EXPECT_EQ(o.out.rfind("failed: ", 0), 0u) << o.out;
  EXPECT_NE(o.err.find("step failed at t = 0 s"), std::string::npos) << o.err;
  const auto summary = ParseJsonFile(out + "/summary.json");
  ASSERT_TRUE(summary);
  EXPECT_EQ(summary->Find("status")->string, "failed");
  EXPECT_EQ(ReadCsv(out + "/points.csv").rows.size(), 1u);
}

TEST(Cli, SigintStopsCleanlyWithExitCode130) {
  REQUIRE_CLI();
  const ScopedDir tmp("cli_sigint");
  const std::string out = tmp.path() + "/out";
  // Far too long to finish: 1e-5 s steps for 1000 s.
  const pid_t pid = Spawn(kCli,
                          {"run", kPendulum, "-o", out, "--set", "analysis.step=1e-5", "--set",
                           "analysis.end_time=1000", "--set", "outputs.vtk=false"},
                          tmp.path());
  ASSERT_GT(pid, 0);
  // Wait until the run is under way (a few rows written), then interrupt.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (ReadCsv(out + "/points.csv").rows.size() < 3 &&
         std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  kill(pid, SIGINT);
  const Outcome o = Wait(pid, tmp.path());
  EXPECT_EQ(o.code, 130) << o.err;
  EXPECT_EQ(o.out.rfind("interrupted: ", 0), 0u) << o.out;
  EXPECT_NE(o.err.find("interrupted by SIGINT at t = "), std::string::npos) << o.err;
  const Table points = ReadCsv(out + "/points.csv");
  ASSERT_TRUE(points.well_formed) << points.problem;
  EXPECT_GE(points.rows.size(), 3u);
  const auto summary = ParseJsonFile(out + "/summary.json");
  ASSERT_TRUE(summary);
  EXPECT_EQ(summary->Find("status")->string, "interrupted");
}

// A scheduler's SIGTERM (or a closed terminal's SIGHUP) ends the run like Ctrl-C: every row
// collected is flushed, both tables end at the same row, and the summary states the signal,
// the current counts and that row count.
TEST(Cli, SigtermAndSighupEndTheRunWithConsistentFilesAndSayWhichSignal) {
  REQUIRE_CLI();
  for (const int signal : {SIGTERM, SIGHUP}) {
    const ScopedDir tmp("cli_sigterm");
    const std::string out = tmp.path() + "/out";
    const pid_t pid = Spawn(kCli,
                            {"run", kPendulum, "-o", out, "--set", "analysis.step=1e-5", "--set",
                             "analysis.end_time=1000", "--set", "outputs.vtk=false", "--set",
                             "outputs.interval=1e-4", "--set", "outputs.max_rows=1e9"},
                            tmp.path());
    ASSERT_GT(pid, 0);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (ReadCsv(out + "/points.csv").rows.size() < 3 &&
           std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    kill(pid, signal);
    const Outcome o = Wait(pid, tmp.path());
    const std::string name = signal == SIGTERM ? "SIGTERM" : "SIGHUP";
    EXPECT_EQ(o.code, 128 + signal) << name << ": " << o.err;
    EXPECT_EQ(o.out.rfind("terminated: ", 0), 0u) << o.out;
    EXPECT_NE(o.err.find("terminated by " + name + " at t = "), std::string::npos) << o.err;
    const auto summary = ParseJsonFile(out + "/summary.json");
    ASSERT_TRUE(summary);
    EXPECT_EQ(summary->Find("status")->string, "terminated");
    ASSERT_NE(summary->Find("signal"), nullptr);
    EXPECT_EQ(summary->Find("signal")->string, name);
    const Table points = ReadCsv(out + "/points.csv"), joints = ReadCsv(out + "/joints.csv");
    ASSERT_TRUE(points.well_formed) << points.problem;
    ASSERT_TRUE(joints.well_formed) << joints.problem;
    const double rows = summary->Find("outputs.rows")->number;
    EXPECT_GE(rows, 3.0);
    EXPECT_EQ(static_cast<double>(points.rows.size()), rows);
    EXPECT_EQ(static_cast<double>(joints.rows.size()), rows);
    EXPECT_EQ(points.rows.back()[0], summary->Find("outputs.last_row_time")->number);
    EXPECT_EQ(joints.rows.back()[0], points.rows.back()[0]);
    // Current counts: the steps up to the stop (rows every 10 steps of 1e-5 s).
    const double steps = summary->Find("steps")->number;
    EXPECT_GE(steps, 10.0 * (rows - 1.0));
    EXPECT_LT(steps, 10.0 * rows);
    EXPECT_NEAR(summary->Find("time")->number, 1e-5 * steps, 1e-12);
  }
}

// Starts the program in a child process with a resource limit (and SIGXFSZ ignored, so that
// writes beyond RLIMIT_FSIZE fail with EFBIG instead of killing it).
Outcome RunCliWithLimit(const std::vector<std::string>& args, const std::string& dir, int resource,
                        rlim_t limit) {
  std::filesystem::create_directories(dir);
  std::vector<std::string> argv_text = {kCli};
  argv_text.insert(argv_text.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : argv_text) argv.push_back(a.data());
  argv.push_back(nullptr);
  const std::string out = dir + "/stdout.txt", err = dir + "/stderr.txt";
  const pid_t pid = fork();
  if (pid == 0) {  // only async-signal-safe calls until exec
    const int fo = open(out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int fe = open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fo < 0 || fe < 0 || dup2(fo, 1) < 0 || dup2(fe, 2) < 0) _exit(127);
    const rlimit r{limit, limit};
    if (setrlimit(resource, &r) != 0) _exit(127);
    signal(SIGXFSZ, SIG_IGN);
    execv(kCli, argv.data());
    _exit(127);
  }
  EXPECT_GT(pid, 0);
  return Wait(pid, dir);
}

// Any exception main() did not expect (here: out of memory under a 48 MiB address-space
// limit, in which the pendulum runs, building a GRM with 10000 elements per soft body) is
// reported with exit code 3, never an abort.
// A static solve driven past a turning point (tests/data/slider_crank.yaml) stops with exit
// status 1 and names the limit point and its load factor. It used to run without end: the CPU
// limit (SIGXCPU, exit 152) is the time-out guard.
TEST(Cli, StaticSolvePastATurningPointStopsWithExitOneAtTheLimitPoint) {
  REQUIRE_CLI();
  const ScopedDir tmp("cli_limit_point");
  const std::string out = tmp.path() + "/out";
  const Outcome o = RunCliWithLimit(
      {"run", std::string(SCREWFEM_TEST_DATA_DIR) + "/slider_crank.yaml", "-o", out, "--quiet"},
      tmp.path(), RLIMIT_CPU, 20);
  ASSERT_EQ(o.code, 1) << o.out << o.err;
  EXPECT_NE(o.err.find("static solution stopped at load factor 0.3251"), std::string::npos)
      << o.err;
  EXPECT_NE(o.err.find("limit point at load factor 0.3251"), std::string::npos) << o.err;
  const auto summary = ParseJsonFile(out + "/summary.json");
  ASSERT_TRUE(summary);
  EXPECT_EQ(summary->Find("status")->string, "failed");
  EXPECT_TRUE(summary->Find("static_solution.limit_point")->boolean);
  // The path up to the limit point: one row per converged step, x_B = 0.3 + 0.2 s.
  const Table points = ReadCsv(out + "/points.csv");
  ASSERT_TRUE(points.well_formed) << points.problem;
  ASSERT_EQ(points.columns[1], "load_factor");
  ASSERT_GE(points.rows.size(), 3u);
  const auto x = static_cast<std::size_t>(points.Column("slider.x"));
  for (const std::vector<double>& row : points.rows) EXPECT_NEAR(row[x], 0.3 + 0.2 * row[1], 1e-12);
  EXPECT_GT(points.rows.back()[1], 0.325);
}

TEST(Cli, OutOfMemoryIsReportedWithExitCodeThree) {
  REQUIRE_CLI();
  if (test::kAddressSanitizer)
    GTEST_SKIP() << "AddressSanitizer reserves more address space than the limit";
  const ScopedDir tmp("cli_oom");
  const std::string grm = std::string(SCREWFEM_SOURCE_DIR) + "/examples/grm/grm_rigid.yaml";
  const rlim_t limit = rlim_t{48} << 20;
  const Outcome fits = RunCliWithLimit(
      {"run", kPendulum, "-o", tmp.path() + "/small", "--set", "analysis.end_time=0.01"},
      tmp.path(), RLIMIT_AS, limit);
  ASSERT_EQ(fits.code, 0) << "the limit leaves no room for a small run: " << fits.err;
  const Outcome o = RunCliWithLimit({"run", grm, "-o", tmp.path() + "/out", "--set",
                                     "defaults.elements=10000", "--set", "outputs.vtk=false"},
                                    tmp.path(), RLIMIT_AS, limit);
  EXPECT_EQ(o.code, 3) << o.err;
  EXPECT_NE(o.err.find("internal error: out of memory"), std::string::npos) << o.err;
}

// A full disk, made deterministic by a 30000-byte file size limit: the first batch of rows
// (64 KiB) does not fit. Both tables end on a complete row, at the same row, and the summary
// says which file failed, why and how many rows the tables hold; exit code 2.
TEST(Cli, WriteErrorLeavesCompleteRowsAndASummaryThatSaysSo) {
  REQUIRE_CLI();
  const ScopedDir tmp("cli_full");
  const std::string out = tmp.path() + "/out";
  const Outcome o = RunCliWithLimit(
      {"run", kPendulum, "-o", out, "--set", "outputs.interval=0", "--set", "outputs.vtk=false"},
      tmp.path(), RLIMIT_FSIZE, 30000);
  EXPECT_EQ(o.code, 2) << o.err;
  EXPECT_EQ(o.out.rfind("failed: ", 0), 0u) << o.out;
  EXPECT_NE(o.err.find("points.csv: File too large"), std::string::npos) << o.err;
  const auto summary = ParseJsonFile(out + "/summary.json");
  ASSERT_TRUE(summary);
  EXPECT_EQ(summary->Find("status")->string, "failed");
  EXPECT_NE(summary->Find("message")->string.find("points.csv: File too large"), std::string::npos);
  const Table points = ReadCsv(out + "/points.csv"), joints = ReadCsv(out + "/joints.csv");
  ASSERT_TRUE(points.well_formed) << points.problem;
  ASSERT_TRUE(joints.well_formed) << joints.problem;
  const double rows = summary->Find("outputs.rows")->number;
  EXPECT_GT(rows, 10.0);
  EXPECT_LT(rows, 501.0);
  EXPECT_EQ(static_cast<double>(points.rows.size()), rows);
  EXPECT_EQ(static_cast<double>(joints.rows.size()), rows);
  EXPECT_EQ(points.rows.back()[0], summary->Find("outputs.last_row_time")->number);
  EXPECT_EQ(joints.rows.back()[0], points.rows.back()[0]);
  EXPECT_LE(std::filesystem::file_size(out + "/points.csv"), 30000u);
}

// When not even the first summary fits (200 bytes), the run stops before it starts and
// leaves no header-only tables that no summary explains.
TEST(Cli, WriteErrorBeforeTheFirstSummaryLeavesNoTables) {
  REQUIRE_CLI();
  const ScopedDir tmp("cli_full_start");
  const std::string out = tmp.path() + "/out";
  const Outcome o = RunCliWithLimit({"run", kPendulum, "-o", out}, tmp.path(), RLIMIT_FSIZE, 200);
  EXPECT_EQ(o.code, 2) << o.err;
  EXPECT_NE(o.err.find("summary.json: File too large"), std::string::npos) << o.err;
  for (const char* file : {"/points.csv", "/joints.csv", "/summary.json", "/vtk"})
    EXPECT_FALSE(std::filesystem::exists(out + file)) << file;
}

// Waits until the run writing `out` has recorded a few rows.
void WaitForRows(const std::string& out) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (ReadCsv(out + "/points.csv").rows.size() < 3 &&
         std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
}

// A second run into the folder of a running run is refused with exit code 2, naming the
// process; the lock dies with its process, even when that is killed.
TEST(Cli, OutputDirectoryInUseByARunningRunIsRefusedNamingItsProcess) {
  REQUIRE_CLI();
  const ScopedDir tmp("cli_lock");
  const std::string out = tmp.path() + "/out";
  std::filesystem::create_directories(tmp.path() + "/first");
  const pid_t pid = Spawn(kCli,
                          {"run", kPendulum, "-o", out, "--set", "analysis.step=1e-5", "--set",
                           "analysis.end_time=1000", "--set", "outputs.vtk=false"},
                          tmp.path() + "/first");
  ASSERT_GT(pid, 0);
  WaitForRows(out);
  const std::vector<std::string> second = {
      "run", kPendulum, "-o", out, "--force", "--set", "analysis.end_time=0.01"};
  Outcome o = RunCli(second, tmp.path() + "/second");
  EXPECT_EQ(o.code, 2) << o.err;
  EXPECT_NE(o.err.find("is in use by another screwfem run (process " + std::to_string(pid) + ")"),
            std::string::npos)
      << o.err;
  EXPECT_GE(ReadCsv(out + "/points.csv").rows.size(), 3u);  // the first run's files untouched
  kill(pid, SIGKILL);
  Wait(pid, tmp.path() + "/first");
  o = RunCli(second, tmp.path() + "/second");
  EXPECT_EQ(o.code, 0) << o.err;
}

// A folder with an earlier run's results is refused unless --force, which removes
// screwfem's files only: no stale frames or tables survive, and vtk/ goes with vtk: false.
TEST(Cli, EarlierResultsAreReplacedOnlyWithForce) {
  REQUIRE_CLI();
  const ScopedDir tmp("cli_force");
  const std::string out = tmp.path() + "/out";
  Outcome o =
      RunCli({"run", kPendulum, "-o", out, "--set", "outputs.vtk_interval=0.01"}, tmp.path());
  ASSERT_EQ(o.code, 0) << o.err;
  ASSERT_TRUE(std::filesystem::exists(out + "/vtk/frame_00050.vtp"));
  std::ofstream(out + "/notes.txt") << "mine\n";
  std::ofstream(out + "/vtk/camera.pvsm") << "mine\n";
  o = RunCli({"run", kPendulum, "-o", out, "--set", "analysis.end_time=0.1"}, tmp.path());
  EXPECT_EQ(o.code, 2);
  EXPECT_NE(o.err.find("holds the results of an earlier run"), std::string::npos) << o.err;
  EXPECT_NE(o.err.find("--force"), std::string::npos) << o.err;
  EXPECT_EQ(ReadCsv(out + "/points.csv").rows.size(), 51u);  // untouched
  // --force: the new run's 2 frames only (t = 0, 0.1), listed and on disk.
  o = RunCli({"run", kPendulum, "-o", out, "--force", "--set", "analysis.end_time=0.1"},
             tmp.path());
  ASSERT_EQ(o.code, 0) << o.err;
  int frames = 0;
  for (const auto& e : std::filesystem::directory_iterator(out + "/vtk"))
    frames += e.path().extension() == ".vtp" ? 1 : 0;
  EXPECT_EQ(frames, 2);
  EXPECT_EQ(ReadCsv(out + "/points.csv").rows.size(), 11u);
  // vtk: false leaves no frames of the earlier run behind.
  o = RunCli({"run", kPendulum, "-o", out, "--force", "--set", "outputs.vtk=false"}, tmp.path());
  ASSERT_EQ(o.code, 0) << o.err;
  EXPECT_FALSE(std::filesystem::exists(out + "/vtk/motion.pvd"));
  EXPECT_FALSE(std::filesystem::exists(out + "/vtk/frame_00000.vtp"));
  EXPECT_TRUE(std::filesystem::exists(out + "/vtk/camera.pvsm"));  // not screwfem's
  EXPECT_EQ(ReadFile(out + "/notes.txt"), "mine\n");
}

TEST(Cli, CheckPrintsCountsWithoutRunning) {
  REQUIRE_CLI();
  const ScopedDir tmp("cli_check");
  const Outcome o = RunCli({"check", kPendulum}, tmp.path());
  ASSERT_EQ(o.code, 0) << o.err;
  EXPECT_NE(o.out.find("1 rigid bodies, 1 joints"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("nv = 7, nc = 6"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("\n  outputs: about 51 rows per table, 6 ParaView frames "
                       "(outputs.max_rows 1000000)\n"),
            std::string::npos)
      << o.out;
}

// `check` refuses a scene estimated past outputs.max_rows (here step: auto over 10 s with a
// row every 1e-5 s: 1e6 + 1 rows, above the default limit), naming the settings; exit 2.
TEST(Cli, CheckRefusesAScenePastMaxRows) {
  REQUIRE_CLI();
  const ScopedDir tmp("cli_check_rows");
  const Outcome o =
      RunCli({"check", kPendulum, "--set", "analysis.step=auto", "--set", "analysis.tolerance=1e-6",
              "--set", "analysis.end_time=10", "--set", "outputs.interval=1e-5"},
             tmp.path());
  EXPECT_EQ(o.code, 2) << o.out << o.err;
  EXPECT_NE(o.out.find("  outputs: about 1000001 rows per table, 101 ParaView frames "
                       "(outputs.max_rows 1000000)"),
            std::string::npos)
      << o.out;
  EXPECT_EQ(o.err,
            "error: outputs.max_rows: the run would record about 1000001 rows in each table, "
            "above the limit of 1000000 (outputs.max_rows); record less often (outputs.interval) "
            "or raise outputs.max_rows\n");
  const Outcome run = RunCli({"run", kPendulum, "-o", tmp.path() + "/out", "--set",
                              "analysis.step=auto", "--set", "analysis.tolerance=1e-6", "--set",
                              "analysis.end_time=10", "--set", "outputs.interval=1e-5"},
                             tmp.path());
  EXPECT_EQ(run.code, 2);
  EXPECT_EQ(run.err, o.err);
  EXPECT_FALSE(std::filesystem::exists(tmp.path() + "/out/points.csv"));
}

// Static runs speak of the load factor: the result line, and a write error (which stops the
// path at once: 2000 load steps, the first 64 KiB of rows past a 30000-byte limit).
TEST(Cli, StaticRunsNameTheLoadFactorAndStopAtAWriteError) {
  REQUIRE_CLI();
  const ScopedDir tmp("cli_static");
  const std::string finger = std::string(SCREWFEM_SOURCE_DIR) + "/examples/tendon/finger.yaml";
  Outcome o = RunCli({"run", finger, "-o", tmp.path() + "/ok", "--set", "analysis.type=static"},
                     tmp.path());
  ASSERT_EQ(o.code, 0) << o.err;
  EXPECT_EQ(o.out.rfind("completed: load factor λ = 1, 10 load steps, ", 0), 0u) << o.out;
  o = RunCli({"check", finger, "--set", "analysis.type=static"}, tmp.path());
  EXPECT_NE(o.out.find("\n  analysis: static, load factor λ from 0 to 1 in 10 load steps (loads "
                       "at t = 2 s)\n"),
            std::string::npos)
      << o.out;
  const std::string out = tmp.path() + "/full";
  o = RunCliWithLimit({"run", finger, "-o", out, "--set", "analysis.type=static", "--set",
                       "analysis.load_steps=2000", "--set", "outputs.vtk=false"},
                      tmp.path(), RLIMIT_FSIZE, 30000);
  EXPECT_EQ(o.code, 2) << o.err;
  EXPECT_EQ(o.out.rfind("failed: load factor λ = ", 0), 0u) << o.out;
  EXPECT_EQ(o.err.rfind("cannot write at load factor λ = ", 0), 0u) << o.err;
  EXPECT_NE(o.err.find(": File too large; the tables hold the "), std::string::npos) << o.err;
  const auto summary = ParseJsonFile(out + "/summary.json");
  ASSERT_TRUE(summary);
  EXPECT_EQ(summary->Find("status")->string, "failed");
  EXPECT_LT(summary->Find("static_solution.load_steps")->number, 1000.0);  // of 2000
}

// A link planted at the lock file's name is refused, naming it; what it points to is untouched.
TEST(Cli, ALinkInTheOutputFolderIsRefused) {
  REQUIRE_CLI();
  const ScopedDir tmp("cli_link");
  const std::string out = tmp.path() + "/out", victim = tmp.path() + "/victim.txt";
  std::filesystem::create_directories(out);
  std::ofstream(victim) << "precious\n";
  std::filesystem::create_symlink(victim, out + "/.screwfem.lock");
  const Outcome o = RunCli({"run", kPendulum, "-o", out, "--force"}, tmp.path());
  EXPECT_EQ(o.code, 2);
  EXPECT_EQ(o.err, "error: " + out +
                       "/.screwfem.lock is a symbolic link; screwfem writes its files into the "
                       "output directory itself and never through a link: remove the link or "
                       "choose another output directory\n");
  EXPECT_EQ(ReadFile(victim), "precious\n");
}

bool PythonHasMatplotlib(const std::string& dir) {
  if (access("/usr/bin/python3", X_OK) != 0) return false;
  return Wait(Spawn("/usr/bin/python3", {"-c", "import matplotlib, numpy"}, dir), dir).code == 0;
}

TEST(Cli, PlotDrawsPointsJointsAndSnapshots) {
  REQUIRE_CLI();
  const ScopedDir tmp("cli_plot");
  if (!PythonHasMatplotlib(tmp.path())) GTEST_SKIP() << "no /usr/bin/python3 with matplotlib";
  const std::string run_a = tmp.path() + "/fine", run_b = tmp.path() + "/coarse";
  ASSERT_EQ(RunCli({"run", kPendulum, "-o", run_a, "-q"}, tmp.path()).code, 0);
  ASSERT_EQ(
      RunCli({"run", kPendulum, "-o", run_b, "-q", "--set", "analysis.step=5e-3"}, tmp.path()).code,
      0);
  const std::string figs = tmp.path() + "/figs";
  const Outcome o = RunCli(
      {"plot", run_a, run_b, "-o", figs, "--points", "tip", "--times", "0,0.25,0.5"}, tmp.path());
  ASSERT_EQ(o.code, 0) << o.err;
  for (const char* f :
       {"point_tip.png", "joint_hinge.png", "snapshots_fine.png", "snapshots_coarse.png"}) {
    const std::string path = figs + "/" + f;
    ASSERT_TRUE(std::filesystem::is_regular_file(path)) << path;
    EXPECT_EQ(ReadFile(path).substr(1, 3), "PNG") << path;
  }
  // Clear errors for missing inputs.
  Outcome bad = RunCli({"plot", tmp.path() + "/nothing", "-o", figs}, tmp.path());
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("error: "), std::string::npos) << bad.err;
  std::filesystem::create_directories(tmp.path() + "/empty");
  bad = RunCli({"plot", tmp.path() + "/empty", "-o", figs}, tmp.path());
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("points.csv not found"), std::string::npos) << bad.err;
  bad = RunCli({"plot", run_a, "-o", figs, "--points", "P8"}, tmp.path());
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("point 'P8' is not recorded"), std::string::npos) << bad.err;
}

TEST(Cli, PlotAnimateWritesOneGifPicturePerFrame) {
  REQUIRE_CLI();
  const ScopedDir tmp("cli_animate");
  if (!PythonHasMatplotlib(tmp.path())) GTEST_SKIP() << "no /usr/bin/python3 with matplotlib";
  const std::string run = tmp.path() + "/swing";
  ASSERT_EQ(RunCli({"run", kPendulum, "-o", run, "-q"}, tmp.path()).code, 0);  // 6 frames
  const std::string figs = tmp.path() + "/figs";
  const Outcome o = RunCli({"plot", run, "-o", figs, "--animate"}, tmp.path());
  ASSERT_EQ(o.code, 0) << o.err;
  const std::string gif = ReadFile(figs + "/animation_swing.gif");
  ASSERT_EQ(gif.substr(0, 4), "GIF8");
  // One image descriptor (0x2C after a graphic control extension) per ParaView frame.
  std::size_t images = 0;
  for (std::size_t i = gif.find("\x21\xF9\x04"); i != std::string::npos;
       i = gif.find("\x21\xF9\x04", i + 1))
    images += gif.size() > i + 8 && gif[i + 8] == '\x2C' ? 1 : 0;
  EXPECT_EQ(images, 6u);
}

TEST(Cli, VersionPrintsTheProjectVersion) {
  REQUIRE_CLI();
  const ScopedDir tmp("cli_version");
  const Outcome o = RunCli({"--version"}, tmp.path());
  EXPECT_EQ(o.code, 0) << o.err;
  EXPECT_EQ(o.out, std::string("screwfem ") + SCREWFEM_VERSION + "\n");
}

TEST(Cli, ViewWritesOneSelfContainedPage) {
  REQUIRE_CLI();
  const ScopedDir tmp("cli_view");
  const std::string out = tmp.path() + "/out";
  ASSERT_EQ(RunCli({"run", kPendulum, "-o", out, "-q"}, tmp.path()).code, 0);
  const Outcome o = RunCli({"view", out}, tmp.path());  // default: OUTDIR/view.html
  ASSERT_EQ(o.code, 0) << o.err;
  EXPECT_EQ(o.out, out + "/view.html\n");
  const std::string html = ReadFile(out + "/view.html");
  EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0u);
  EXPECT_NE(html.find("\"name\":\"pendulum\""), std::string::npos);  // the case name
  EXPECT_NE(html.find("var REVISION=\"111\""), std::string::npos);   // three.js inlined
  EXPECT_EQ(html.find("<script src"), std::string::npos);            // nothing fetched
  // A run without ParaView frames: a clear error, exit status 2.
  const std::string novtk = tmp.path() + "/novtk";
  ASSERT_EQ(
      RunCli({"run", kPendulum, "-o", novtk, "-q", "--set", "outputs.vtk=false"}, tmp.path()).code,
      0);
  const Outcome bad = RunCli({"view", novtk, "-o", tmp.path() + "/x.html"}, tmp.path());
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("has no ParaView frames"), std::string::npos) << bad.err;
  EXPECT_FALSE(std::filesystem::exists(tmp.path() + "/x.html"));
}

TEST(Cli, PlotScriptCanBeOverriddenByTheEnvironment) {
  REQUIRE_CLI();
  const ScopedDir tmp("cli_plot_env");
  const Outcome o = RunCli({"plot", tmp.path(), "-o", tmp.path() + "/figs"}, tmp.path(),
                           {"SCREWFEM_PLOT_SCRIPT=" + tmp.path() + "/no_such_script.py"});
  EXPECT_EQ(o.code, 2);
  EXPECT_NE(o.err.find("no_such_script.py not found"), std::string::npos) << o.err;
}

// `screwfem sweep` runs `python3 -m screwfem sweep` (tests/python/test_sweep.py covers it); the
// package directory is compiled in and overridable, with a clear error when it is wrong.
TEST(Cli, SweepPackageDirectoryCanBeOverriddenByTheEnvironment) {
  REQUIRE_CLI();
  const ScopedDir tmp("cli_sweep_env");
  const Outcome o =
      RunCli({"sweep", kPendulum, "--grid", "analysis.rho_inf=0.8,1", "-o", tmp.path() + "/sweep"},
             tmp.path(), {"SCREWFEM_PYTHONPATH=" + tmp.path() + "/no_such_dir"});
  EXPECT_EQ(o.code, 2);
  EXPECT_NE(o.err.find("Python package screwfem not found in " + tmp.path() + "/no_such_dir"),
            std::string::npos)
      << o.err;
  EXPECT_FALSE(std::filesystem::exists(tmp.path() + "/sweep"));
}

}  // namespace
}  // namespace screwfem::cli_test
