// The input limits of docs/scene-format.md ("Limits"): each limit is hit with a clear
// message, and hostile or huge inputs end quickly with bounded memory. The heavy cases run in
// a forked child (the CLI, or ParseScene in-process) under a wall-clock guard, with its peak
// resident memory read from wait4 (and, outside the sanitizer build, an address-space limit
// of 1 GiB, so that a regression fails fast instead of exhausting the machine).
#include <gtest/gtest.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "run_test_util.h"
#include "screwfem/io/scene.h"
#include "screwfem/model/errors.h"

namespace screwfem::limits_test {
namespace {

using test::ReadFile;
using test::ScopedDir;

constexpr bool kSanitized = test::kAddressSanitizer;

#ifdef SCREWFEM_CLI_PATH
constexpr const char* kCli = SCREWFEM_CLI_PATH;
#else
constexpr const char* kCli = nullptr;
#endif

// Each heavy case must end within 5 s of CPU time (60 s under the sanitizers); a wall-clock
// guard kills the child after 30 s (120 s) so that a regression cannot hang the suite. CPU
// time rather than wall time: the test machine is shared, and its load must not fail a test.
constexpr double kCpuSeconds = kSanitized ? 60.0 : 5.0;
constexpr int kGuardSeconds = kSanitized ? 120 : 30;
constexpr long kMemoryLimitKb = 1024L * 1024L;  // 1 GiB

struct ChildResult {
  int code = -1;  // exit status, or 128 + signal (SIGKILL: the guard fired)
  long max_rss_kb = 0;
  double seconds = 0.0;      // wall
  double cpu_seconds = 0.0;  // user + system
  std::string err;           // what the child wrote to stderr
};

// Runs `body` in a forked child (stderr to a file), killed after kGuardSeconds.
ChildResult RunChild(const std::string& dir, const std::function<int()>& body) {
  std::filesystem::create_directories(dir);
  const std::string err_path = dir + "/stderr.txt";
  const auto t0 = std::chrono::steady_clock::now();
  const pid_t pid = fork();
  if (pid == 0) {
    const int fd = open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(fd, 2);
    if (!kSanitized) {
      rlimit as{static_cast<rlim_t>(kMemoryLimitKb) * 1024,
                static_cast<rlim_t>(kMemoryLimitKb) * 1024};
      setrlimit(RLIMIT_AS, &as);
    }
    _exit(body());
  }
  ChildResult r;
  int status = 0;
  rusage usage{};
  for (;;) {
    const pid_t w = wait4(pid, &status, WNOHANG, &usage);
    if (w == pid) break;
    if (std::chrono::steady_clock::now() - t0 > std::chrono::seconds(kGuardSeconds)) {
      kill(pid, SIGKILL);
      wait4(pid, &status, 0, &usage);
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.max_rss_kb = usage.ru_maxrss;
  r.cpu_seconds = static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
                  1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
  r.err = ReadFile(err_path);
  return r;
}

// The screwfem program in a child (argv as given).
ChildResult RunCli(const std::string& dir, const std::vector<std::string>& args) {
  return RunChild(dir, [&] {
    std::vector<std::string> text = {kCli};
    text.insert(text.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (std::string& a : text) argv.push_back(a.data());
    argv.push_back(nullptr);
    const int null = open("/dev/null", O_WRONLY);
    dup2(null, 1);
    execv(kCli, argv.data());
    return 127;
  });
}

// ParseScene in a child: 0 parsed, 2 InputError (message on stderr), 3 anything else.
ChildResult ParseInChild(const std::string& dir, const std::string& text,
                         const std::vector<std::string>& overrides = {}) {
  return RunChild(dir, [&] {
    try {
      ParseScene(text, "scene.yaml", overrides);
      return 0;
    } catch (const InputError& e) {
      std::fputs(e.what(), stderr);
      return 2;
    } catch (...) {
      return 3;
    }
  });
}

void ExpectBounded(const ChildResult& r) {
  EXPECT_NE(r.code, 128 + SIGKILL) << "the child ran longer than " << kGuardSeconds << " s";
  EXPECT_LT(r.cpu_seconds, kCpuSeconds) << "CPU time of the child";
  EXPECT_LT(r.max_rss_kb, kMemoryLimitKb) << "peak resident memory of the child";
}

// The message of ParseScene's InputError, or "" when it parses.
std::string ParseError(const std::string& text, const std::vector<std::string>& overrides = {}) {
  try {
    ParseScene(text, "scene.yaml", overrides);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// Concatenation by appends (GCC 12 warns falsely on "literal" + std::string temporaries).
std::string Cat(std::initializer_list<std::string_view> pieces) {
  std::string s;
  for (std::string_view p : pieces) s += p;
  return s;
}

std::string Pendulum() { return ReadFile(std::string(SCREWFEM_TEST_DATA_DIR) + "/pendulum.yaml"); }

#define REQUIRE_CLI()                                                                           \
  do {                                                                                          \
    if (kCli == nullptr) GTEST_SKIP() << "the build did not say where the screwfem program is"; \
  } while (0)

// --- file size -------------------------------------------------------------------------------

TEST(Limits, CheckOfDevZeroStopsAtTheFileSizeLimit) {
  REQUIRE_CLI();
  ScopedDir tmp("limits_devzero");
  const ChildResult r = RunCli(tmp.path(), {"check", "/dev/zero"});
  ExpectBounded(r);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("/dev/zero: the scene file is larger than 16 MiB (the limit)"),
            std::string::npos)
      << r.err;
}

TEST(Limits, SceneTextAndOverridesHaveSizeLimits) {
  EXPECT_NE(ParseError(std::string(kMaxSceneBytes + 1, ' ')).find("larger than 16 MiB"),
            std::string::npos);
  const std::string huge = Cat({"name=", std::string(kMaxOverrideBytes, 'x')});
  EXPECT_NE(ParseError(Pendulum(), {huge}).find("an override is longer than 1 MiB"),
            std::string::npos);
}

// --- YAML nodes, aliases and nesting ---------------------------------------------------------

// a0 holds 10 scalars, a1 ... a4 ten aliases of the previous anchor each (a4: 111,111 nodes),
// a5 seven aliases of a4 (777,778 nodes: the document is still below the limit), and 2500
// aliases of a5 follow (12.8 KB in all). The old parser counted the whole anchor on every
// alias, even after the limit had fired: more than 120 s for this file.
std::string AliasBomb() {
  std::string s = "a0: &a0 [x, x, x, x, x, x, x, x, x, x]\n";
  for (int k = 1; k <= 5; ++k) {
    // Appends only (GCC 12 warns falsely on "literal" + std::to_string).
    const std::string kk = std::to_string(k), prev = std::to_string(k - 1);
    std::string line = "a";
    line += kk;
    line += ": &a";
    line += kk;
    line += " [";
    for (int i = 0; i < (k == 5 ? 7 : 10); ++i) {
      line += i ? ", *a" : "*a";
      line += prev;
    }
    s += line;
    s += "]\n";
  }
  s += "bomb: [";
  for (int i = 0; i < 2500; ++i) s += i ? ", *a5" : "*a5";
  return s + "]\n";
}

TEST(Limits, AliasBombStopsAtTheNodeLimit) {
  REQUIRE_CLI();
  ScopedDir tmp("limits_alias");
  const std::string file = tmp.path() + "/bomb.yaml";
  std::ofstream(file) << AliasBomb();
  const ChildResult r = RunCli(tmp.path(), {"check", file});
  ExpectBounded(r);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("bomb.yaml:7:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("the document expands to more than 1000000 nodes (aliases?)"),
            std::string::npos)
      << r.err;
}

TEST(Limits, NestingDeeperThanOneHundredLevelsIsAnError) {
  const std::string ok = Cat({"a: ", std::string(99, '['), std::string(99, ']'), "\n"});
  EXPECT_EQ(ParseError(ok).find("nested"), std::string::npos);
  const std::string deep = Cat({"a: ", std::string(100, '['), std::string(100, ']'), "\n"});
  EXPECT_NE(
      ParseError(deep).find("scene.yaml:1:103: lists and maps nested more than 100 levels deep"),
      std::string::npos)
      << ParseError(deep);
}

// --- overrides ---------------------------------------------------------------------------------

TEST(Limits, OneMegabyteOverridePathEndsQuicklyWithAClearMessage) {
  ScopedDir tmp("limits_override");
  // 500000 components: rejected by the path-depth limit.
  std::string deep;
  for (int i = 0; i < 499999; ++i) deep += "a.";
  deep += "a=1";
  ChildResult r = ParseInChild(tmp.path(), Pendulum(), {deep});
  ExpectBounded(r);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("the key path has more than 16 components"), std::string::npos)
      << r.err.substr(0, 300);
  // One 1 MB component: an unknown top-level key (with linear work on the way).
  const std::string wide = std::string(999998, 'k') + "=1";
  r = ParseInChild(tmp.path(), Pendulum(), {wide});
  ExpectBounded(r);
  EXPECT_EQ(r.code, 2) << r.err.substr(0, 300);
  EXPECT_NE(r.err.find("unknown key 'kkkk"), std::string::npos) << r.err.substr(0, 300);
  // Sixteen components of 60 KB each: created keys share the override text.
  std::string sixteen = "outputs";
  for (int i = 0; i < 15; ++i)
    sixteen += Cat({".", std::string(60000, static_cast<char>('a' + i))});
  r = ParseInChild(tmp.path(), Pendulum(), {sixteen + "=1"});
  ExpectBounded(r);
  EXPECT_EQ(r.code, 2) << r.err.substr(0, 300);
  EXPECT_NE(r.err.find("unknown key 'aaaa"), std::string::npos) << r.err.substr(0, 300);
}

TEST(Limits, OverridePathsUpToSixteenComponents) {
  std::string path = "analysis";
  for (int i = 0; i < 15; ++i) path += ".x";
  EXPECT_EQ(ParseError(Pendulum(), {path + "=1"}).find("components"), std::string::npos);
  EXPECT_NE(ParseError(Pendulum(), {path + ".x=1"}).find("more than 16 components"),
            std::string::npos);
}

// --- numbers, elements, steps ------------------------------------------------------------------

TEST(Limits, ExpressionsLongerThan400CharactersAreErrors) {
  std::string expr = "1";
  while (expr.size() < 399) expr += "+1";
  const std::string scene = Pendulum();
  EXPECT_EQ(ParseError(scene, {Cat({"analysis.step=", expr, "0"})}).find("too long"),  // 400
            std::string::npos);
  const std::string long_expr = expr + "+1";  // 401 characters
  EXPECT_NE(ParseError(scene, {Cat({"analysis.step=", long_expr})}).find("expression too long"),
            std::string::npos);
  const std::string nested = Cat({std::string(70, '('), "1", std::string(70, ')')});
  EXPECT_NE(ParseError(scene, {Cat({"analysis.step=", nested})}).find("nested too deeply"),
            std::string::npos);
}

const char* kRodScene = R"(
points: {O: [0, 0, 0], E: [1, 0, 0]}
materials: {m: {E: 1e6, nu: 0.45, density: 1000}}
sections: {s: {shape: circle, radius: 0.01, material: m}}
bodies:
  arm: {type: soft, from: O, to: E, section: s}
joints:
  clamp: {type: fixed, at: O, between: [ground, arm]}
analysis: {type: static}
)";

std::string RodScene() { return kRodScene; }

TEST(Limits, ElementsPerRodAndPerSceneAreBounded) {
  EXPECT_EQ(ParseError(RodScene(), {"bodies.arm.elements=100000"}), "");
  EXPECT_NE(ParseError(RodScene(), {"bodies.arm.elements=100001"})
                .find("expected an integer from 1 to 100000"),
            std::string::npos);
  // A path of 11 segments with 100000 elements each: 1.1e6 elements in all.
  std::string path = "[";
  for (int i = 0; i <= 11; ++i) {
    path += i ? ", [" : "[";
    path += std::to_string(i);
    path += ", 0, 0]";
  }
  path += "]";
  std::string scene = RodScene();
  scene.replace(scene.find("from: O, to: E"), 14, Cat({"path: ", path, ", elements: 100000"}));
  const std::string error = ParseError(scene);
  EXPECT_NE(error.find("more than 1000000 elements in all (the limit)"), std::string::npos)
      << error;
}

TEST(Limits, MoreThanABillionTimeStepsIsAnError) {
  EXPECT_EQ(ParseError(Pendulum(), {"analysis.end_time=999", "analysis.step=1e-6"}), "");
  EXPECT_NE(ParseError(Pendulum(), {"analysis.end_time=1001", "analysis.step=1e-6"})
                .find("more than 1e9 time steps"),
            std::string::npos);
}

// --- a large valid scene -------------------------------------------------------------------------

// 500 welds (3000 constraint rows) and a 100000-element rod: `check` asked for 14.4 GB
// (the dense redundancy check) before.
TEST(Limits, FiveHundredWeldsAndAHundredThousandElementRodCheckQuickly) {
  REQUIRE_CLI();
  ScopedDir tmp("limits_welds");
  std::string bodies, joints;
  for (int i = 0; i < 499; ++i) {
    const std::string x = std::to_string(0.2 * i + 0.1), n = std::to_string(i);
    for (const std::string& piece :
         {std::string("  b"), n, std::string(": {type: rigid, at: ["), x,
          std::string(", 0.5, 0], mass: 0.1, inertia: [1e-4, 1e-4, 1e-4]}\n")})
      bodies += piece;
    for (const std::string& piece :
         {std::string("  w"), n, std::string(": {type: fixed, at: ["), x,
          std::string(", 0, 0], between: [b"), n, std::string(", arm]}\n")})
      joints += piece;
  }
  std::string scene = RodScene();
  scene.replace(scene.find("E: [1, 0, 0]"), 12, "E: [100, 0, 0]");
  scene.replace(scene.find("section: s}"), 11, "section: s, elements: 100000}");
  scene.insert(scene.find("joints:\n"), bodies);
  scene.insert(scene.find("analysis:"), joints);
  const std::string file = tmp.path() + "/welds.yaml";
  std::ofstream(file) << scene;
  const ChildResult r = RunCli(tmp.path(), {"check", file});
  ExpectBounded(r);
  EXPECT_EQ(r.code, 0) << r.err;
}

// --- memory (docs/limits.md, "Memory") ----------------------------------------------------------

// 1000 sphere obstacles beside a 100,000-element rod (a 60 KB scene): 1e8 pairs. `check` ran
// 66 s up to 3.4 GB and ran out of memory; it now refuses them from their count.
TEST(Limits, ThousandSphereObstaclesAndAHundredThousandElementRodAreRefusedQuickly) {
  REQUIRE_CLI();
  ScopedDir tmp("limits_obstacles");
  std::string scene = RodScene();
  scene.replace(scene.find("E: [1, 0, 0]"), 12, "E: [100, 0, 0]");
  scene.replace(scene.find("section: s}"), 11, "section: s, elements: 100000}");
  std::string obstacles = "contact:\n  obstacles:\n";
  for (int i = 0; i < 1000; ++i)
    for (const std::string& piece :
         {std::string("    o"), std::to_string(i), std::string(": {type: sphere, center: ["),
          std::to_string(0.1 * i), std::string(", 1, 0], radius: 0.05}\n")})
      obstacles += piece;
  scene.insert(scene.find("analysis:"), obstacles);
  const std::string file = tmp.path() + "/obstacles.yaml";
  std::ofstream(file) << scene;
  const ChildResult r = RunCli(tmp.path(), {"check", file});
  ExpectBounded(r);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("obstacles.yaml: contact: the moving shapes and obstacles make 100000000 "
                       "pairs, more than 10000000 (the limit: every pair is tested at every "
                       "assembly). Exclude the shapes that cannot reach an obstacle"),
            std::string::npos)
      << r.err;
}

// 10,000 free spheres on a plane: every two may touch. Their links in the band made a band of
// 59,999 (86 GB of LU factors for a run); they now stay off the band, with a warning.
TEST(Limits, TenThousandSpheresOnAPlaneCheckQuicklyWithASmallBand) {
  REQUIRE_CLI();
  ScopedDir tmp("limits_spheres");
  std::string scene = "bodies:\n";
  for (int i = 0; i < 10000; ++i) {
    const std::string n = std::to_string(i), x = std::to_string(0.2 * (i % 100)),
                      y = std::to_string(0.2 * (i / 100));
    for (const std::string& piece :
         {std::string("  b"), n, std::string(": {type: rigid, at: ["), x, std::string(", "), y,
          std::string(", 0.1], mass: 0.1, inertia: [1e-4, 1e-4, 1e-4], free: true, shapes: "
                      "[{type: sphere, center: ["),
          x, std::string(", "), y, std::string(", 0.1], radius: 0.05}]}\n")})
      scene += piece;
  }
  scene +=
      "contact:\n  obstacles:\n    ground: {type: plane, point: [0, 0, 0], normal: [0, 0, 1]}\n"
      "analysis: {type: dynamic, end_time: 0.01, step: 1e-3}\n";
  const std::string file = tmp.path() + "/spheres.yaml";
  std::ofstream(file) << scene;
  const ChildResult r = RunChild(tmp.path(), [&] {
    const int out = open((tmp.path() + "/stdout.txt").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(out, 1);
    std::vector<std::string> text = {kCli, "check", file};
    std::vector<char*> argv;
    for (std::string& a : text) argv.push_back(a.data());
    argv.push_back(nullptr);
    execv(kCli, argv.data());
    return 127;
  });
  ExpectBounded(r);
  EXPECT_EQ(r.code, 0) << r.err;
  const std::string out = ReadFile(tmp.path() + "/stdout.txt");
  EXPECT_NE(out.find("unknowns: nv = 60000, nc = 0 (0 redundant constraint rows), bandwidth 5\n"),
            std::string::npos)
      << out;
  // auto takes the sparse LU (10,000 nodes may be coupled off the band, more than the Woodbury
  // room of 128), whose pattern takes the pairs that touch: no warning about band links.
  EXPECT_NE(out.find("    sparse LU factors of the iteration matrix: "), std::string::npos) << out;
  EXPECT_EQ(out.find("warning: the 49995000 pairs of contact entities"), std::string::npos) << out;
}

TEST(Limits, MaxMemoryRefusesAModelBeyondItNamingTheBandedFactors) {
  REQUIRE_CLI();
  ScopedDir tmp("limits_max_memory");
  std::string scene = RodScene();
  scene.replace(scene.find("section: s}"), 11, "section: s, elements: 100000}");
  const std::string file = tmp.path() + "/rod.yaml";
  std::ofstream(file) << scene;
  ChildResult r = RunCli(tmp.path(), {"check", file, "--max-memory", "10M"});
  ExpectBounded(r);
  EXPECT_EQ(r.code, 2) << r.err;
  // 600,012 unknowns (a rod of 100,000 elements and its clamp's 6 rows), bandwidth 11:
  // 600012 x 34 x 8 bytes + 52 bytes each.
  EXPECT_NE(r.err.find("rod.yaml: the model's solver workspace needs about "), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find(", more than the memory limit of 10 MiB (set by --max-memory or "
                       "max_memory; --max-memory SIZE or max_memory= change it): the largest "
                       "part is the banded LU factors of the iteration matrix, 185 MiB (600012 "
                       "unknowns (nv = 600006, nc = 6) x 34 band entries (bandwidth 11: 3 x 11 + "
                       "1) x 8 bytes)"),
            std::string::npos)
      << r.err;
  r = RunCli(tmp.path(), {"check", file, "--max-memory", "1G"});
  ExpectBounded(r);
  EXPECT_EQ(r.code, 0) << r.err;
  r = RunCli(tmp.path(), {"check", file, "--max-memory", "lots"});
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.err,
            "error: --max-memory: expected a size such as 8G or 512M (K, M, G, T: powers of "
            "1024), got 'lots'\n");
}

// --- run-time input tables ------------------------------------------------------------------------

std::string InputScene() {
  std::string scene = Pendulum();
  scene.insert(scene.find("analysis:"), "inputs: {u: 0.0}\n");
  return scene;
}

// `--inputs /dev/zero` read the whole device: out of memory after 33 s under a 1 GiB cap.
TEST(Limits, InputTableOfDevZeroStopsAtItsSizeLimit) {
  REQUIRE_CLI();
  ScopedDir tmp("limits_inputs_devzero");
  const std::string file = tmp.path() + "/scene.yaml";
  std::ofstream(file) << InputScene();
  const ChildResult r =
      RunCli(tmp.path(), {"run", file, "-o", tmp.path() + "/out", "--inputs", "/dev/zero"});
  ExpectBounded(r);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(r.err, "error: /dev/zero: the input table is larger than 64 MiB (the limit)\n");
}

// Ctrl-C while the input table is read (a FIFO whose writer sends nothing): the run ends at
// once with 130 (it was ignored for 69 s).
TEST(Limits, InputTableReadIsInterruptedBySigint) {
  REQUIRE_CLI();
  ScopedDir tmp("limits_inputs_fifo");
  const std::string file = tmp.path() + "/scene.yaml";
  std::ofstream(file) << InputScene();
  const std::string fifo = tmp.path() + "/table.csv";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  const auto t0 = std::chrono::steady_clock::now();
  const pid_t pid = fork();
  if (pid == 0) {
    const int err = open((tmp.path() + "/stderr.txt").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(err, 2);
    const int null = open("/dev/null", O_WRONLY);
    dup2(null, 1);
    std::vector<std::string> text = {kCli,       "run", file, "-o", tmp.path() + "/out",
                                     "--inputs", fifo};
    std::vector<char*> argv;
    for (std::string& a : text) argv.push_back(a.data());
    argv.push_back(nullptr);
    execv(kCli, argv.data());
    _exit(127);
  }
  // A writer that writes part of a header and keeps the FIFO open.
  const int writer = open(fifo.c_str(), O_WRONLY);
  ASSERT_GE(writer, 0);
  ASSERT_EQ(write(writer, "t,", 2), 2);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  kill(pid, SIGINT);
  int status = 0;
  bool ended = false;
  for (int i = 0; i < 2000 && !ended; ++i) {
    ended = waitpid(pid, &status, WNOHANG) == pid;
    if (!ended) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!ended) {
    kill(pid, SIGKILL);
    waitpid(pid, &status, 0);
  }
  close(writer);
  ASSERT_TRUE(ended) << "the run did not end on SIGINT";
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 130);
  EXPECT_LT(seconds, 9.0);
  EXPECT_EQ(ReadFile(tmp.path() + "/stderr.txt"),
            "interrupted: " + fifo + ": reading the input table was interrupted\n");
}

}  // namespace
}  // namespace screwfem::limits_test
