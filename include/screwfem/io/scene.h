// Scenes: a model plus what to do with it (analysis) and what to record (outputs).
// A scene file (YAML, docs/scene-format.md) is parsed into a Scene; running a Scene writes
// results into a directory (see run.h).
#pragma once

#include <string>
#include <vector>

#include "screwfem/assemble/assemble.h"
#include "screwfem/model/data.h"
#include "screwfem/solve/dynamics.h"
#include "screwfem/solve/rest.h"
#include "screwfem/solve/statics.h"
#include "screwfem/solve/stop.h"

namespace screwfem {

enum class AnalysisKind { kStatic, kDynamic };
template <>
struct EnumNames<AnalysisKind> {
  static constexpr std::array<EnumName<AnalysisKind>, 2> kValues = {{
      {AnalysisKind::kStatic, "static", "Newton on the Lie group with load stepping"},
      {AnalysisKind::kDynamic, "dynamic", "generalized-alpha time integration"},
  }};
};

struct AnalysisSettings {
  AnalysisKind kind = AnalysisKind::kDynamic;
  double start_time = 0.0;  // [s]
  double end_time = 1.0;    // [s]
  double step = 1e-3;       // [s], dynamic analyses (with adaptive_steps: the first step)
  // step: auto: error-controlled steps (AdaptiveStep; dynamic.absolute_tolerance, ...,
  // min_step, max_step); output rows at times inside a step are interpolated (InterpolateStep).
  bool adaptive_steps = false;
  bool align_steps = true;  // shorten steps so that profile breakpoints fall on step ends
  DynamicOptions dynamic;
  StaticOptions statics;
  // Dynamic analyses may start from a static equilibrium of the loads at start_time.
  bool static_preload = false;
  // analysis.threads: the threads of the assembly (assemble.h, SetAssemblyThreads), >= 1 or
  // kAutoThreads (every core for a model of at least kParallelMinElements rod elements).
  int threads = kAutoThreads;
  // analysis.stop_at_rest (dynamic analyses): the run ends, completed, once the scene has been
  // at rest for the criterion's hold time (solve/rest.h; summary.json's rest_time).
  RestCriterion stop_at_rest;
};

// A recorded point: a point fixed in a node frame (rigid body, joint side or rod node), or a
// point along a rod at arc length s from its first node.
struct OutputPoint {
  std::string name;            // column prefix, e.g. "P8"
  int node = -1;               // node whose frame carries the point (node points)
  Vec3 offset = Vec3::Zero();  // in that node frame [m]
  int rod = -1;                // rod points: rod index and arc length
  double arc_length = 0.0;
};

struct OutputJoint {
  std::string name;  // column prefix, e.g. "J3"
  int joint = -1;
};

// Scene files without outputs.interval (vtk_interval) record rows (ParaView frames) every
// whole number of steps closest to (end_time - start_time) / kDefaultOutputRows
// (kDefaultVtkFrames), at least every step: smooth curves, and a ParaView animation, at a cost
// that does not grow with the number of steps (docs/scene-format.md, "outputs"). A scene that
// gives interval but not vtk_interval writes frames at that interval.
inline constexpr int kDefaultOutputRows = 1000;
inline constexpr int kDefaultVtkFrames = 100;
// outputs.max_rows: its default and the largest value a scene may give.
inline constexpr long kDefaultMaxRows = 1000000;
inline constexpr long kMaxMaxRows = 1000000000;

// Encoding of the ParaView frames (vtk.h).
enum class VtkFormat { kBinary, kAscii };
template <>
struct EnumNames<VtkFormat> {
  static constexpr std::array<EnumName<VtkFormat>, 2> kValues = {{
      {VtkFormat::kBinary, "binary", "raw binary arrays appended to the XML, doubles exact"},
      {VtkFormat::kAscii, "ascii",
       "arrays as text, each double the shortest text that reads back exactly"},
  }};
};

struct OutputSpec {
  std::vector<OutputPoint> points;
  std::vector<OutputJoint> joints;
  double interval = 0.0;      // [s] between recorded rows; 0: every step
  bool vtk = true;            // ParaView files under vtk/
  double vtk_interval = 0.0;  // [s]; 0: same as interval
  VtkFormat vtk_format = VtkFormat::kBinary;
  // rod_fields.csv (writers.h, RodFieldColumns): the section strain and stress of every rod.
  bool rod_fields = false;
  // [s] between its rows (0: every step; start and end included, as rows); < 0: at the rows
  // of points.csv. Static analyses: every load step, whatever the interval.
  double rod_fields_interval = -1.0;
  // The most output times a run records (docs/scene-format.md, "outputs"): rows of each table
  // (a long table's block of rows at one time counts once), rod_fields.csv times and ParaView
  // frames, each. `check` and `run` refuse a scene estimated to record more (EstimateOutputs,
  // run.h), and a run that reaches it ends as failed. In [1, kMaxMaxRows].
  long max_rows = kDefaultMaxRows;
  // reactions.csv and energy.csv (writers.h, ReactionColumns and EnergyColumns), at the rows of
  // points.csv; off, the table is neither written nor computed (the energy row is about 8 %
  // of a rigid GRM step, the reactions 2 %: docs/benchmarks.md, "Cost of the outputs").
  bool reactions = true;
  bool energy = true;
};

struct Scene {
  std::string source;  // file name (for messages and the summary)
  std::string name;    // scene title
  Model model;
  AnalysisSettings analysis;
  OutputSpec outputs;
  // Named points of the scene (world coordinates in the reference configuration), for
  // documentation and plotting.
  std::vector<std::pair<std::string, Vec3>> named_points;
};

// Size limits of the input (docs/limits.md): a scene file or text, and one override string.
// LoadScene reads at most kMaxSceneBytes + 64 KiB bytes, so a file without a size (/dev/zero,
// a pipe) stops there.
inline constexpr std::size_t kMaxSceneBytes = std::size_t{16} << 20;    // 16 MiB
inline constexpr std::size_t kMaxOverrideBytes = std::size_t{1} << 20;  // 1 MiB

// Parses and compiles a scene. `overrides` are "key.path=value" strings applied to the YAML
// tree before compilation (e.g. "analysis.step=5e-4", "bodies.arm56.elements=8").
// Throws InputError with a message "FILE:LINE:COLUMN: FIELD: what was expected".
// `stop` is polled while the file is read (InputError "PATH: reading the scene file was
// interrupted" when it asks to stop).
Scene LoadScene(const std::string& path, const std::vector<std::string>& overrides = {},
                const StopRequest& stop = {});
Scene ParseScene(const std::string& yaml_text, const std::string& source_name,
                 const std::vector<std::string>& overrides = {});

}  // namespace screwfem
