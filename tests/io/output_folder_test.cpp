// The output folder of a run (run.h, writers.h): the one list of screwfem's files that the
// writers create from and --force removes; no file written through a link; a write error that
// stops the run at once, static paths included, with every table cut at the same output time;
// outputs.max_rows, estimated ahead and kept at run time; static runs that speak of the load
// factor; tendons.csv at the applied (scaled) tension.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "run_test_util.h"
#include "screwfem/io/run.h"
#include "screwfem/io/scene.h"
#include "screwfem/io/writers.h"
#include "screwfem/model/errors.h"

namespace screwfem::output_folder_test {
namespace {

namespace fs = std::filesystem;
using test::ParseJsonFile;
using test::ReadCsv;
using test::ReadFile;
using test::ScopedDir;
using test::Table;

const std::string kPendulum = std::string(SCREWFEM_TEST_DATA_DIR) + "/pendulum.yaml";
const std::string kFinger = std::string(SCREWFEM_SOURCE_DIR) + "/examples/tendon/finger.yaml";

void WriteText(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

// The message of the InputError that f throws ("" when it throws none).
template <class F>
std::string InputErrorOf(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// A file size limit for this process (RLIMIT_FSIZE, soft) with SIGXFSZ ignored, so that a
// write beyond it fails with EFBIG as on a full disk; both restored at the end of the scope.
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    getrlimit(RLIMIT_FSIZE, &old_);
    rlimit r = old_;
    r.rlim_cur = bytes;
    setrlimit(RLIMIT_FSIZE, &r);
    old_handler_ = std::signal(SIGXFSZ, SIG_IGN);
  }
  FileSizeLimit(const FileSizeLimit&) = delete;
  FileSizeLimit& operator=(const FileSizeLimit&) = delete;
  ~FileSizeLimit() {
    setrlimit(RLIMIT_FSIZE, &old_);
    std::signal(SIGXFSZ, old_handler_);
  }

 private:
  rlimit old_{};
  void (*old_handler_)(int) = SIG_DFL;
};

// ---- one list of screwfem's files ---------------------------------------------------------------

TEST(OutputFiles, TheListNamesEveryTableAndTheFramePatternOnly) {
  for (const char* name :
       {"summary.json", "summary.json.tmp", "joints.json", "joints.json.tmp", "points.csv",
        "joints.csv", "reactions.csv", "energy.csv", "tendons.csv", "forces.csv", "actuators.csv",
        "contacts.csv", "pair_contacts.csv", "rod_fields.csv"})
    EXPECT_TRUE(IsOutputFileName(name, false)) << name;
  for (const char* name : {"notes.txt", "points.csv.bak", ".screwfem.lock", "vtk", "motion.pvd",
                           "frame_00000.vtp", "Points.csv"})
    EXPECT_FALSE(IsOutputFileName(name, false)) << name;
  for (const char* name :
       {"motion.pvd", "motion.pvd.tmp", "frame_00000.vtp", "frame_12345.vtp", "frame_123456.vtp"})
    EXPECT_TRUE(IsOutputFileName(name, true)) << name;
  for (const char* name : {"frame_1.vtp", "frame_0000a.vtp", "frame_00000.vtp.bak",
                           "xframe_00000.vtp", "frame_00000.vtu", "points.csv", "mine.pvd"})
    EXPECT_FALSE(IsOutputFileName(name, true)) << name;
  // The writers can create no other name.
  ScopedDir dir("own_names");
  OutputFolder folder;
  folder.Open(dir.path(), false);
  EXPECT_THROW(folder.Create("notes.txt"), std::logic_error);
  const int fd = folder.Create(kPointsFile);
  EXPECT_GE(fd, 0);
  if (fd >= 0) close(fd);
}

// Every file a run writes (here one with tendons, force elements and every ParaView file) is
// on the list; --force on a folder holding every listed file, frames of many digits and files
// of the user's removes exactly the listed ones and nothing else.
TEST(OutputFiles, ForceRemovesExactlyTheListedFilesAndARunWritesNoOther) {
  ScopedDir dir("own_files");
  const std::string out = dir.path() + "/out";
  fs::create_directories(out + "/vtk");
  for (const char* name : kOutputFiles) WriteText(out + "/" + name, "old\n");
  for (const char* name : kVtkFiles) WriteText(out + "/vtk/" + name, "old\n");
  for (const char* name : {"frame_00000.vtp", "frame_00999.vtp", "frame_1234567.vtp"})
    WriteText(out + "/vtk/" + name, "old\n");
  const std::vector<std::string> mine = {"notes.txt", "points.csv.bak", "vtk/frame_1.vtp",
                                         "vtk/frame_00000.vtp.orig", "vtk/camera.pvsm"};
  for (const std::string& name : mine) WriteText(out + "/" + name, "mine\n");

  const Scene s = LoadScene(
      kFinger, {"analysis.end_time=0.02", "outputs.interval=0.01", "outputs.vtk_interval=0.01"});
  const std::string refused = InputErrorOf([&] { RunScene(s, out); });
  EXPECT_EQ(refused.rfind("output directory " + out +
                              " holds the results of an earlier run (summary.json, "
                              "summary.json.tmp, joints.json, joints.json.tmp, ...)",
                          0),
            0u)
      << refused;
  RunOptions force;
  force.replace_results = true;
  const RunResult r = RunScene(s, out, force);
  ASSERT_TRUE(r.ok) << r.message;

  std::set<std::string> written,
      expected = {".screwfem.lock",      "energy.csv",          "forces.csv",
                  "joints.csv",          "joints.json",         "points.csv",
                  "reactions.csv",       "summary.json",        "tendons.csv",
                  "vtk/frame_00000.vtp", "vtk/frame_00001.vtp", "vtk/frame_00002.vtp",
                  "vtk/motion.pvd"};
  for (const std::string& name : mine) expected.insert(name);
  for (const fs::directory_entry& e : fs::recursive_directory_iterator(out))
    if (!e.is_directory()) written.insert(fs::relative(e.path(), out).string());
  EXPECT_EQ(written, expected);
  for (const std::string& name : mine) EXPECT_EQ(ReadFile(out + "/" + name), "mine\n") << name;
  // Every file the run wrote is one of the list's (the lock aside).
  for (const std::string& name : written) {
    if (std::find(mine.begin(), mine.end(), name) != mine.end() || name == ".screwfem.lock")
      continue;
    const bool vtk = name.rfind("vtk/", 0) == 0;
    EXPECT_TRUE(IsOutputFileName(vtk ? name.substr(4) : name, vtk)) << name;
  }
  // A stale table alone (here pair_contacts.csv, which the finger does not write) is an
  // earlier run's result too.
  ScopedDir lone("own_files_lone");
  WriteText(lone.path() + "/pair_contacts.csv", "t\n");
  const std::string message = InputErrorOf([&] { RunScene(s, lone.path()); });
  EXPECT_NE(message.find("holds the results of an earlier run (pair_contacts.csv)"),
            std::string::npos)
      << message;
}

// ---- no writing through links --------------------------------------------------------------------

// A link planted in the output folder at one of screwfem's names (a table, the lock, vtk/) is
// refused, with or without --force, naming it; the file or folder it points to is untouched.
TEST(OutputFolder, LinksInsideTheFolderAreRefusedAndNeverFollowed) {
  ScopedDir dir("links");
  const std::string victim = dir.path() + "/victim.txt";
  WriteText(victim, "precious\n");
  const Scene s = LoadScene(kPendulum, {"analysis.end_time=0.01"});
  RunOptions force;
  force.replace_results = true;
  for (const char* name : {"tendons.csv", "points.csv", ".screwfem.lock", "summary.json.tmp"}) {
    const std::string out = dir.path() + "/out_" + std::string(name).substr(1, 4);
    fs::create_directories(out);
    fs::create_symlink(victim, out + "/" + name);
    for (const bool replace : {false, true}) {
      const std::string message =
          InputErrorOf([&] { RunScene(s, out, replace ? force : RunOptions{}); });
      EXPECT_EQ(message, out + "/" + name +
                             " is a symbolic link; screwfem writes its files into the output "
                             "directory itself and never through a link: remove the link or "
                             "choose another output directory")
          << name;
    }
    EXPECT_EQ(ReadFile(victim), "precious\n") << name;
    EXPECT_TRUE(fs::is_symlink(out + "/" + name)) << name;
  }
  // vtk/ linked to a folder of frames elsewhere: refused, its frames kept.
  const std::string frames = dir.path() + "/frames";
  fs::create_directories(frames);
  WriteText(frames + "/frame_00000.vtp", "mine\n");
  const std::string out = dir.path() + "/out_vtk";
  fs::create_directories(out);
  fs::create_directory_symlink(frames, out + "/vtk");
  for (const bool replace : {false, true}) {
    const std::string message =
        InputErrorOf([&] { RunScene(s, out, replace ? force : RunOptions{}); });
    EXPECT_EQ(message.rfind(out + "/vtk is a symbolic link; ", 0), 0u) << message;
  }
  EXPECT_EQ(ReadFile(frames + "/frame_00000.vtp"), "mine\n");
  // A link named like a frame inside vtk/.
  const std::string out2 = dir.path() + "/out_frame";
  fs::create_directories(out2 + "/vtk");
  fs::create_symlink(victim, out2 + "/vtk/frame_00003.vtp");
  const std::string message = InputErrorOf([&] { RunScene(s, out2, force); });
  EXPECT_EQ(message.rfind(out2 + "/vtk/frame_00003.vtp is a symbolic link; ", 0), 0u) << message;
  EXPECT_EQ(ReadFile(victim), "precious\n");
}

// A hard link of a file elsewhere at a table's name: --force removes the name only (the other
// file keeps its text); and the writers refuse to empty a file with other hard links.
TEST(OutputFolder, HardLinksAreNeverWrittenThrough) {
  ScopedDir dir("hard_links");
  const std::string victim = dir.path() + "/victim.txt", out = dir.path() + "/out";
  WriteText(victim, "precious\n");
  fs::create_directories(out);
  fs::create_hard_link(victim, out + "/points.csv");
  RunOptions force;
  force.replace_results = true;
  const RunResult r = RunScene(LoadScene(kPendulum, {"analysis.end_time=0.01"}), out, force);
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_EQ(ReadFile(victim), "precious\n");
  EXPECT_EQ(fs::hard_link_count(victim), 1u);
  fs::create_hard_link(victim, out + "/energy.csv.link");
  OutputFolder folder;
  folder.Open(out, false);
  fs::remove(out + "/energy.csv");
  fs::rename(out + "/energy.csv.link", out + "/energy.csv");
  EXPECT_EQ(folder.Create(kEnergyFile), -1);
  EXPECT_EQ(errno, EMLINK);
  EXPECT_EQ(folder.CreateError(kEnergyFile, EMLINK),
            "cannot create " + out +
                "/energy.csv: it is a hard link of another file, which screwfem would overwrite; "
                "remove it or choose another output directory");
  EXPECT_EQ(ReadFile(victim), "precious\n");
}

// ---- write errors -------------------------------------------------------------------------------

// Tables written at the same output times: after a write error in any of them every one is
// cut at the same output event, long tables (several rows per event) included.
TEST(CsvWriter, FlushTogetherCutsEveryTableAtTheSameOutputEvent) {
  ScopedDir dir("flush_together");
  OutputFolder folder;
  folder.Open(dir.path(), false);
  CsvWriter wide, lng;
  wide.Open(folder, kPointsFile, {"a", "b"});
  lng.Open(folder, kContactsFile, {"pair", "f"});
  {
    const FileSizeLimit limit(4000);
    for (long long key = 0; key < 200; ++key) {
      const double t = 0.001 * static_cast<double>(key);
      wide.WriteRow(t, {1.0, 2.0}, key);
      for (int pair = 0; pair < 3; ++pair)
        lng.WriteRow(t, {static_cast<double>(pair), 12.5}, key);  // 3 rows per event
    }
    const CsvWriter* failed = CsvWriter::FlushTogether({&wide, &lng});
    ASSERT_EQ(failed, &lng);
    EXPECT_EQ(errno, EFBIG);
  }
  EXPECT_TRUE(wide.failed());
  EXPECT_FALSE(wide.WriteRow(1.0, {1.0, 2.0}, 400));
  wide.Close();
  lng.Close();
  const Table a = ReadCsv(dir.path() + "/points.csv"), b = ReadCsv(dir.path() + "/contacts.csv");
  ASSERT_TRUE(a.well_formed) << a.problem;
  ASSERT_TRUE(b.well_formed) << b.problem;
  ASSERT_GT(a.rows.size(), 10u);
  EXPECT_EQ(b.rows.size(), 3 * a.rows.size());  // whole events only
  EXPECT_EQ(b.rows.back()[0], a.rows.back()[0]);
  EXPECT_EQ(b.rows.back()[1], 2.0);
  EXPECT_EQ(wide.last_key(), static_cast<long long>(a.rows.size()) - 1);
  EXPECT_EQ(lng.last_key(), wide.last_key());
}

// A resting sphere on a fixed one (pair_contacts.csv) and one on the ground plane
// (contacts.csv), both active at every output time: after a write error all the tables end at
// the same last time.
TEST(WriteError, ContactTablesAreCutAtTheLastTimeOfTheOtherTables) {
  const std::string text = R"(gravity: [0, 0, -9.81]
bodies:
  low: {type: rigid, at: [0, 0, 1], mass: 1, inertia: [1, 1, 1], fixed: true,
        shapes: [{type: sphere, center: [0, 0, 1], radius: 0.1}]}
  top: {type: rigid, at: [0, 0, 1.1999519], mass: 1, inertia: [0.004, 0.004, 0.004],
        free: true, shapes: [{type: sphere, center: [0, 0, 1.1999519], radius: 0.1}]}
  ball: {type: rigid, at: [1, 0, 0.0999519], mass: 1, inertia: [0.004, 0.004, 0.004],
         free: true, shapes: [{type: sphere, center: [1, 0, 0.0999519], radius: 0.1}]}
contact:
  stiffness: 1e5
  onset: 1e-4
  obstacles:
    ground: {type: plane, point: [0, 0, 0], normal: [0, 0, 1]}
analysis: {type: dynamic, end_time: 1, step: 1e-3}
outputs: {points: {p: {body: top, at: [0, 0, 1.1999519]}}, interval: 0, vtk: false}
)";
  // (At rest: the penetration branch's gap onset/2 - m g / k = -4.81e-5 m under 1 kg.)
  for (const rlim_t bytes : {rlim_t{30000}, rlim_t{90000}}) {
    ScopedDir dir("contact_cut_" + std::to_string(bytes));
    const Scene s = ParseScene(text, "rest.yaml");
    RunResult r;
    {
      const FileSizeLimit limit(bytes);
      r = RunScene(s, dir.path());
    }
    ASSERT_FALSE(r.ok);
    EXPECT_TRUE(r.io_error);
    EXPECT_NE(r.message.find(": File too large; the tables hold the "), std::string::npos)
        << r.message;
    const Table points = ReadCsv(dir.path() + "/points.csv");
    ASSERT_TRUE(points.well_formed) << points.problem;
    ASSERT_GT(points.rows.size(), 10u);
    const double last = points.rows.back()[0];
    for (const char* file :
         {"/joints.csv", "/reactions.csv", "/energy.csv", "/contacts.csv", "/pair_contacts.csv"}) {
      const Table t = ReadCsv(dir.path() + file);
      ASSERT_TRUE(t.well_formed) << file << ": " << t.problem;
      ASSERT_FALSE(t.rows.empty()) << file;
      EXPECT_EQ(t.rows.back()[0], last) << file << " at a limit of " << bytes << " bytes";
    }
    // One active pair of each kind at every time: as many rows as points.csv.
    EXPECT_EQ(ReadCsv(dir.path() + "/contacts.csv").rows.size(), points.rows.size());
    EXPECT_EQ(ReadCsv(dir.path() + "/pair_contacts.csv").rows.size(), points.rows.size());
    const auto summary = ParseJsonFile(dir.path() + "/summary.json");
    ASSERT_TRUE(summary);
    EXPECT_EQ(summary->Find("outputs.last_row_time")->number, last);
  }
}

// A write error on a static path stops the solve at once (it used to solve the rest of the
// path, 2000 load steps here, after writing "failed"): the summary says failed, where (the
// load factor λ, not a time) and why, and counts the load steps solved.
TEST(WriteError, StaticPathStopsAtTheNextNewtonIterationAndNamesTheLoadFactor) {
  ScopedDir dir("static_write_error");
  const Scene s =
      LoadScene(kFinger, {"analysis.type=static", "analysis.load_steps=2000", "outputs.vtk=false"});
  RunResult r;
  {
    const FileSizeLimit limit(30000);
    r = RunScene(s, dir.path());
  }
  ASSERT_FALSE(r.ok);
  EXPECT_TRUE(r.io_error);
  const auto summary = ParseJsonFile(dir.path() + "/summary.json");
  ASSERT_TRUE(summary);
  EXPECT_EQ(summary->Find("status")->string, "failed");
  const double steps = summary->Find("static_solution.load_steps")->number;
  const Table points = ReadCsv(dir.path() + "/points.csv");
  ASSERT_TRUE(points.well_formed) << points.problem;
  ASSERT_GT(points.rows.size(), 10u);
  // The failing flush came with the rows of 64 KiB of steps; the solve stopped right there.
  EXPECT_GT(steps, static_cast<double>(points.rows.size()));
  EXPECT_LT(steps, 1000.0);  // of 2000
  EXPECT_EQ(static_cast<double>(r.steps), steps);
  // The rotation of the last converged load step, not 0: the flexor curls the finger, each
  // load step by about 1/2000 of the full curl.
  const double rotation = summary->Find("max_element_rotation")->number;
  EXPECT_EQ(rotation, r.max_element_rotation);
  EXPECT_GT(rotation, 1e-4);
  const double failed_at = 0.0005 * steps, kept = points.rows.back()[1];
  EXPECT_NEAR(kept, 0.0005 * static_cast<double>(points.rows.size()), 1e-12);
  // The file that met the limit first (the largest batch).
  const std::string& message = summary->Find("message")->string;
  const std::size_t from = message.find(dir.path() + "/"), to = message.find(": File too large");
  ASSERT_NE(from, std::string::npos) << message;
  ASSERT_NE(to, std::string::npos) << message;
  const std::string file =
      message.substr(from + dir.path().size() + 1, to - from - dir.path().size() - 1);
  EXPECT_TRUE(IsOutputFileName(file, false)) << file;
  char expected[512];
  std::snprintf(expected, sizeof expected,
                "cannot write at load factor λ = %.9g: %s/%s: File too large; the tables hold "
                "the %zu rows up to load factor λ = %.9g",
                failed_at, dir.path().c_str(), file.c_str(), points.rows.size(), kept);
  EXPECT_EQ(message, expected);
  EXPECT_EQ(r.message, expected);
  EXPECT_NEAR(r.load_factor, failed_at, 1e-12);
  for (const char* table : {"/joints.csv", "/tendons.csv", "/forces.csv", "/energy.csv"}) {
    const Table t = ReadCsv(dir.path() + table);
    ASSERT_TRUE(t.well_formed) << table << ": " << t.problem;
    EXPECT_EQ(t.rows.size(), points.rows.size()) << table;
  }
}

// A dynamic run stops at the step that met the write error (vtk frames larger than the limit:
// the first frame), not at its end time.
TEST(WriteError, DynamicRunStopsAtTheStepThatFailed) {
  ScopedDir dir("dynamic_write_error");
  const Scene s =
      LoadScene(kFinger, {"analysis.end_time=100", "outputs.interval=0", "outputs.vtk=false"});
  RunResult r;
  {
    const FileSizeLimit limit(30000);
    r = RunScene(s, dir.path());
  }
  ASSERT_FALSE(r.ok);
  EXPECT_TRUE(r.io_error);
  EXPECT_LT(r.steps, 2000);
  // It ended at the step whose rows met the error.
  EXPECT_EQ(r.message.rfind(FormatNumbers("cannot write at t = %.9g s: ", r.end_time), 0), 0u)
      << r.message;
  EXPECT_NE(r.message.find("File too large"), std::string::npos) << r.message;
  const auto summary = ParseJsonFile(dir.path() + "/summary.json");
  ASSERT_TRUE(summary);
  EXPECT_EQ(summary->Find("status")->string, "failed");
  EXPECT_EQ(summary->Find("message")->string, r.message);
}

// ---- outputs.max_rows -----------------------------------------------------------------------------

TEST(MaxRows, SceneKeyDefaultAndErrorsWithTheirLocation) {
  const std::string head =
      "gravity: [0, 0, -9.81]\nbodies:\n  b: {type: rigid, at: [0, 0, 0], "
      "mass: 1, inertia: [1, 1, 1], free: true}\n";
  EXPECT_EQ(ParseScene(head, "a.yaml").outputs.max_rows, 1000000);
  EXPECT_EQ(ParseScene(head + "outputs: {max_rows: 2e6}\n", "a.yaml").outputs.max_rows, 2000000);
  EXPECT_EQ(InputErrorOf([&] { ParseScene(head + "outputs: {max_rows: 0}\n", "a.yaml"); }),
            "a.yaml:4:21: outputs.max_rows: expected an integer from 1 to 1000000000, got '0'");
  EXPECT_EQ(InputErrorOf([&] { ParseScene(head + "outputs: {max_rows: 1.5}\n", "a.yaml"); }),
            "a.yaml:4:21: outputs.max_rows: expected an integer, got '1.5'");
  EXPECT_EQ(InputErrorOf([&] { ParseScene(head + "outputs: {max_rows: 2e9}\n", "a.yaml"); }),
            "a.yaml:4:21: outputs.max_rows: expected an integer from 1 to 1000000000, got '2e9'");
}

TEST(MaxRows, EstimatesFollowTheIntervalsAndTheSteps) {
  // Fixed steps of 1 ms over 0.5 s: rows every 0.01 s (51), frames every 0.1 s (6).
  Scene s = LoadScene(kPendulum);
  OutputEstimate e = EstimateOutputs(s, s.outputs);
  EXPECT_EQ(e.rows, 51.0);
  EXPECT_EQ(e.frames, 6.0);
  EXPECT_EQ(e.field_times, 0.0);
  s.outputs.interval = 0.0;  // every step
  EXPECT_EQ(EstimateOutputs(s, s.outputs).rows, 501.0);
  s.outputs.interval = 1e-5;  // below a step: every step
  EXPECT_EQ(EstimateOutputs(s, s.outputs).rows, 501.0);
  // step: auto: from the interval and the duration only (12 steps may write 100,001 rows).
  Scene a =
      LoadScene(kPendulum, {"analysis.step=auto", "analysis.tolerance=1e-6", "analysis.end_time=1",
                            "outputs.interval=1e-5", "outputs.vtk=false"});
  e = EstimateOutputs(a, a.outputs);
  EXPECT_EQ(e.rows, 100001.0);
  EXPECT_EQ(e.frames, 0.0);
  a.outputs.interval = 0.0;
  EXPECT_TRUE(std::isnan(EstimateOutputs(a, a.outputs).rows));  // not known ahead
  // Static: a row per load step and the start.
  const Scene st = LoadScene(kFinger, {"analysis.type=static", "analysis.load_steps=40"});
  EXPECT_EQ(EstimateOutputs(st, st.outputs).rows, 41.0);
}

TEST(MaxRows, RunRefusesAScenePastTheLimitNamingTheSettings) {
  ScopedDir dir("max_rows_refused");
  const Scene a =
      LoadScene(kPendulum, {"analysis.step=auto", "analysis.tolerance=1e-6", "analysis.end_time=1",
                            "outputs.interval=1e-5", "outputs.vtk=false"});
  EXPECT_EQ(EstimateOutputs(a, a.outputs).rows, 100001.0);  // allowed
  const Scene b =
      LoadScene(kPendulum, {"analysis.step=auto", "analysis.tolerance=1e-6", "analysis.end_time=1",
                            "outputs.interval=1e-5", "outputs.max_rows=1e5"});
  const std::string message = InputErrorOf([&] { RunScene(b, dir.path() + "/b"); });
  EXPECT_EQ(message,
            "outputs.max_rows: the run would record about 100001 rows in each table, above the "
            "limit of 100000 (outputs.max_rows); record less often (outputs.interval) or raise "
            "outputs.max_rows");
  EXPECT_FALSE(fs::exists(dir.path() + "/b"));  // refused before anything is written
  const Scene c = LoadScene(
      kPendulum, {"outputs.vtk_interval=0", "outputs.interval=0", "outputs.max_rows=500"});
  EXPECT_EQ(InputErrorOf([&] { RunScene(c, dir.path() + "/c"); }),
            "outputs.max_rows: the run would record about 501 rows in each table, above the limit "
            "of 500 (outputs.max_rows); record less often (outputs.interval) or raise "
            "outputs.max_rows");
  const Scene d = LoadScene(kPendulum, {"outputs.vtk_interval=1e-3", "outputs.max_rows=500"});
  EXPECT_EQ(InputErrorOf([&] { RunScene(d, dir.path() + "/d"); }),
            "outputs.max_rows: the run would record about 501 ParaView frames, above the limit "
            "of 500 (outputs.max_rows); record less often (outputs.vtk_interval) or raise "
            "outputs.max_rows");
  const Scene st =
      LoadScene(kFinger, {"analysis.type=static", "analysis.load_steps=40", "outputs.max_rows=40"});
  EXPECT_EQ(InputErrorOf([&] { RunScene(st, dir.path() + "/st"); }),
            "outputs.max_rows: the run would record about 41 rows in each table, above the limit "
            "of 40 (outputs.max_rows); use fewer load steps (analysis.statics.load_steps) or "
            "raise outputs.max_rows");
}

// step: auto with interval 0 (a row at every accepted step) is not estimated ahead: the run
// stops, as failed, when it reaches the limit, with exactly that many rows on disk.
TEST(MaxRows, RunTimeBoundStopsARunThatReachesTheLimit) {
  ScopedDir dir("max_rows_runtime");
  const Scene s =
      LoadScene(kPendulum, {"analysis.step=auto", "analysis.tolerance=1e-6", "outputs.interval=0",
                            "outputs.vtk=false", "outputs.max_rows=20"});
  const RunResult r = RunScene(s, dir.path());
  ASSERT_FALSE(r.ok);
  EXPECT_FALSE(r.io_error);
  const Table points = ReadCsv(dir.path() + "/points.csv");
  ASSERT_TRUE(points.well_formed) << points.problem;
  ASSERT_EQ(points.rows.size(), 20u);
  EXPECT_LT(r.end_time, 0.5);
  char expected[256];
  std::snprintf(expected, sizeof expected,
                "outputs.max_rows: the run reached 20 rows of the tables (the limit) at t = %.9g "
                "s; record less often (outputs.interval, outputs.vtk_interval, "
                "outputs.rod_fields) or raise outputs.max_rows",
                r.end_time);
  EXPECT_EQ(r.message, expected);
  const auto summary = ParseJsonFile(dir.path() + "/summary.json");
  ASSERT_TRUE(summary);
  EXPECT_EQ(summary->Find("status")->string, "failed");
  EXPECT_EQ(summary->Find("message")->string, expected);
}

// ---- static runs: the load factor -------------------------------------------------------------------

// tendons.csv and forces.csv report what the static solver applies at each load step: the
// tendon's tension and the force element's actuator scaled by the load factor (the finger's
// tension is 50 N at statics.time = the end time), as actuators.csv's applied value is.
TEST(StaticRun, TendonTensionIsTheAppliedScaledTension) {
  ScopedDir dir("static_tension");
  const Scene s = LoadScene(kFinger, {"analysis.type=static", "analysis.load_steps=10"});
  const RunResult r = RunScene(s, dir.path());
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_EQ(r.load_factor, 1.0);
  const Table tendons = ReadCsv(dir.path() + "/tendons.csv");
  ASSERT_TRUE(tendons.well_formed) << tendons.problem;
  ASSERT_EQ(tendons.rows.size(), 10u);
  const auto tension = static_cast<std::size_t>(tendons.Column("flexor.tension"));
  for (const std::vector<double>& row : tendons.rows) EXPECT_EQ(row[tension], 50.0 * row[1]);
  EXPECT_EQ(tendons.rows.front()[1], 0.1);
  EXPECT_EQ(tendons.rows.back()[tension], 50.0);
}

}  // namespace
}  // namespace screwfem::output_folder_test
