// Result tables and the run summary (see run.h for the files): the columns and values of
// points.csv and joints.csv, the list of the files a run writes and the output folder that
// creates them (by a directory descriptor, never through a link), a CSV writer that writes
// whole rows, a small JSON text builder and an atomic file replacement.
#pragma once

#include <array>
#include <cstdio>
#include <initializer_list>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "screwfem/io/scene.h"

namespace screwfem {

// ---- recorded quantities ---------------------------------------------------------------------

// Throws InputError unless every output point names an existing node (or rod, with an arc
// length in [0, rod length]) and every output joint an existing joint; the message names the
// output entry.
void ValidateOutputs(const Model& model, const OutputSpec& outputs);

// Column names after "t": per point P: P.x P.y P.z P.vx P.vy P.vz P.ax P.ay P.az, then
// P.qw P.qx P.qy P.qz (kPointColumns per point).
inline constexpr std::size_t kPointColumns = 13;
std::vector<std::string> PointColumns(const std::vector<OutputPoint>& points);
// Per joint J with one coordinate: J.q J.qd J.qdd J.effort; with k > 1 coordinates the same
// four per coordinate i as J.i.q ...; joints without coordinates (fixed) have no columns.
std::vector<std::string> JointColumns(const Model& model, const std::vector<OutputJoint>& joints);

// The text of joints.json, which describes the joints' coordinates for readers of joints.csv:
//   {"format": "screwfem joints 1", "joints": [{"name", "index" (in the model, as the VTK
//    frames' joint_id), "type" ("revolute", ...), "drive" ("none", "prescribed",
//    "series_elastic", "force"), "drive_coordinate" (or null), "column" (the joints.csv prefix,
//    or null when not recorded), "coordinates": [{"column" (e.g. "J3" or "J7.1", or null),
//    "quantity" ("angle" or "slide"), "unit" ("rad" or "m"), "rate_unit", "acceleration_unit",
//    "effort_unit" ("N m" or "N")}]}]}
// for every joint of the model, in model order. A coordinate is an angle when its basis column
// has a rotation part (so a helical joint's coordinate is its angle), a slide otherwise.
std::string JointsDescriptionJson(const Model& model, const std::vector<OutputJoint>& joints);

// Values of one row (without t), in column order, at data's current state: world position
// [m], velocity [m/s] and acceleration [m/s^2] (assemble/outputs.h) and the orientation of the
// point's frame (FrameQuaternion: the section frame of a point along a rod, the node frame of
// a node point, whatever its offset); joint coordinates [m or rad] and their first and
// second time derivatives, and the effort [N or N m].
// `row` is resized to the number of columns (no allocation once it has that size).
void CalcPointRow(const Model& model, const Data& data, const std::vector<OutputPoint>& points,
                  std::vector<double>* row);
void CalcJointRow(const Model& model, const Data& data, const std::vector<OutputJoint>& joints,
                  std::vector<double>* row);

// (The effort column is JointCoordinateEffort, elements/joint.h.)

// The unit quaternion (w, x, y, z) of a rotation R (world from frame), with the sign fixed so
// that equal frames give equal columns: w >= 0, and when w = 0 the first non-zero of x, y, z
// is positive.
Eigen::Vector4d FrameQuaternion(const Mat3& R);

// tendons.csv: per tendon T of the model, T.length [m], T.rate [m/s], T.tension [N];
// forces.csv: per force element F, F.length [m], F.rate [m/s], F.force [N] (positive: tension)
// (elements/tendon.h, CalcTendonState and CalcForceElementState).
std::vector<std::string> TendonColumns(const Model& model);
std::vector<std::string> ForceColumns(const Model& model);
// The tension and force are those applied at `load_factor` (static analyses: the row's load
// factor, as the solver applies them; CalcTendonState).
void CalcTendonRow(const Model& model, const Data& data, std::vector<double>* row,
                   double load_factor = 1.0);
void CalcForceRow(const Model& model, const Data& data, std::vector<double>* row,
                  double load_factor = 1.0);
// actuators.csv: per actuator A of the model (docs/numerics.md, "Active stress and rest strain"), the column A: its profile's
// value at t (pressure [Pa], activation [-] clamped to [0, 1], or the factor of its vector;
// elements/rod.h, ActuatorValue); in static analyses the applied value is this times the
// load_factor column.
std::vector<std::string> ActuatorColumns(const Model& model);
void CalcActuatorRow(const Model& model, const Data& data, double t, std::vector<double>* row);
// contacts.csv (long format, one row per active contact pair at each output time): pair (index
// into Model::contact_pairs), rod (1: the shape is a rod's, 0: a rigid body's), owner (rod or
// body index), obstacle (index), px py pz (the shape's surface point [m], world), nx ny nz (the
// normal, from the obstacle to the shape), fn [N] (normal force), ftx fty ftz [N] (friction
// force on the shape, world), gap [m] (elements/contact.h, CalcContactState).
std::vector<std::string> ContactColumns();
// The row of pair `pair` into *row (resized once); false when the pair is inactive.
bool CalcContactRow(const Model& model, const Data& data, int pair, std::vector<double>* row);
// pair_contacts.csv (long format, one row per active pair of moving shapes at each output time;
// elements/shape_pair.h, CalcShapePairState): pair (ShapePairKey: the two contact segments,
// a x num_segments + b, the same number at every time for the same two shapes); for side A
// then side B: rod (1: a rod's element capsule, 0: a rigid body's shape), owner (rod or body
// index), element (the rod element's index, -1 for a body); pax pay paz and pbx pby pbz (the two
// surface points [m], world), nx ny nz (the normal, from B to A), fn [N] (normal force),
// ftx fty ftz [N] (friction force on A, world; B carries the opposite), gap [m], part (ShapePair::
// part: 0 or 1 for the two clipped ends of a segment against a box, -1 for a single point).
std::vector<std::string> PairContactColumns();
// The row of pair `pair` (index into data.shape_pairs, as the broad phase found them).
bool CalcPairContactRow(const Model& model, const Data& data, int pair, std::vector<double>* row);
// reactions.csv: per joint J of the model with constraint rows (every joint but free ones,
// passive or driven, recorded or not), in model order: J.Fx J.Fy J.Fz J.Mx J.My J.Mz, the force
// [N] and moment [N m] it transmits to its side B (CalcJointReaction, assemble/outputs.h: world
// components, moment about the joint point on side B). J is the joint's name (J<index> when it
// has none).
std::vector<std::string> ReactionColumns(const Model& model);
void CalcReactionRow(const Model& model, const Data& data, std::vector<double>* row);
// energy.csv: kinetic strain spring gravity total [J] (CalcEnergy), px py pz [kg m/s] and
// Lx Ly Lz [kg m^2/s] (CalcMomentum: world, angular momentum about the world origin).
std::vector<std::string> EnergyColumns();
void CalcEnergyRow(const Model& model, const Data& data, std::vector<double>* row);
// settling.csv (scenes with contact): kinetic [J], speed [m/s] and angular_speed [rad/s] (the
// largest of the free nodes), contacts (active pairs, obstacle and moving), slipping (of them,
// those slipping under the stick law), overlap [m] (the deepest) and overlap_ratio (the deepest
// relative to the pair's smaller round radius): CalcSettlingState (assemble/outputs.h).
std::vector<std::string> SettlingColumns();
// `kinetic`: the state's kinetic energy when the caller has it (energy.csv's row), else NaN.
void CalcSettlingRow(const Model& model, const Data& data, bool dynamics, double kinetic,
                     std::vector<double>* row);
// rod_fields.csv (long format, outputs.rod_fields): at each output time one row per station
// (one per rod element, at its mid arc length): rod s gamma1 gamma2 gamma3 kappa1 kappa2 kappa3
// n1 n2 n3 m1 m2 m3, the values of CalcRodFieldRows (assemble/outputs.h: units, section axes
// and signs).
std::vector<std::string> RodFieldColumns();

// ---- files -----------------------------------------------------------------------------------

// Appends `value` formatted as printf("%.*g", precision, value) would (std::to_chars with a
// precision is specified to match printf, and is several times faster).
void AppendNumber(std::string* text, double value, int precision);
// Appends the shortest decimal text that reads back (strtod, Python float) as exactly `value`
// (std::to_chars without a precision): "0.1" for 0.1, where %.17g writes
// "0.10000000000000001"; infinities and NaN as "inf", "-inf", "nan".
void AppendShortest(std::string* text, double value);

// ---- the output folder -------------------------------------------------------------------------

// The files a run can write into its output folder (run.h describes them): the one list that
// the writers create from (OutputFolder::Create refuses any other name) and that --force
// (RunOptions::replace_results) removes, nothing else. kOutputFiles are in the folder itself,
// kVtkFiles and the frames (IsFrameFileName) in its subfolder kVtkFolder. The lock file
// (kOutputLockFile, run.h) is not a result: it stays.
inline constexpr const char* kSummaryFile = "summary.json";
inline constexpr const char* kJointsDescriptionFile = "joints.json";
inline constexpr const char* kPointsFile = "points.csv";
inline constexpr const char* kJointsFile = "joints.csv";
inline constexpr const char* kReactionsFile = "reactions.csv";
inline constexpr const char* kEnergyFile = "energy.csv";
inline constexpr const char* kTendonsFile = "tendons.csv";
inline constexpr const char* kForcesFile = "forces.csv";
inline constexpr const char* kActuatorsFile = "actuators.csv";
inline constexpr const char* kContactsFile = "contacts.csv";
inline constexpr const char* kPairContactsFile = "pair_contacts.csv";
inline constexpr const char* kRodFieldsFile = "rod_fields.csv";
inline constexpr const char* kSettlingFile = "settling.csv";
inline constexpr const char* kVtkFolder = "vtk";
inline constexpr const char* kCollectionFile = "motion.pvd";
// The temporary files of WriteFileAtomically: the name followed by this.
inline constexpr const char* kTemporarySuffix = ".tmp";
inline constexpr std::array<const char*, 15> kOutputFiles = {
    kSummaryFile,      "summary.json.tmp", kJointsDescriptionFile, "joints.json.tmp",
    kPointsFile,       kJointsFile,        kReactionsFile,         kEnergyFile,
    kTendonsFile,      kForcesFile,        kActuatorsFile,         kContactsFile,
    kPairContactsFile, kRodFieldsFile,     kSettlingFile};
inline constexpr std::array<const char*, 2> kVtkFiles = {kCollectionFile, "motion.pvd.tmp"};
// frame_NNNNN.vtp: "frame_", five or more digits, ".vtp" (VtkWriter's frame files).
bool IsFrameFileName(std::string_view name);
// `name` is one of screwfem's files of the output folder (kOutputFiles), or of its vtk
// subfolder (`vtk`: kVtkFiles and the frames).
bool IsOutputFileName(std::string_view name, bool vtk);

// A folder of results, held open by a directory descriptor (O_DIRECTORY | O_CLOEXEC): every
// file is created relative to it with O_NOFOLLOW, so renaming or replacing the folder's path
// while a run writes cannot redirect its files, and a symbolic link (or another file's hard
// link) planted at one of screwfem's names is refused rather than written through.
class OutputFolder {
 public:
  OutputFolder() = default;
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;
  ~OutputFolder();

  // Opens the folder at `path`, created first (with its parents) when `create`. The path
  // itself may go through links (it is the caller's choice); what is inside may not. Throws
  // InputError naming the path when it cannot.
  void Open(const std::string& path, bool create);
  // Opens subfolder `name` (kVtkFolder) of `parent`, created when `create`; throws InputError
  // when it is a symbolic link or not a folder.
  void OpenSubfolder(const OutputFolder& parent, const char* name, bool create);
  // Creates file `name` (IsOutputFileName, else std::logic_error) for writing, emptied, and
  // returns its descriptor (O_WRONLY | O_CLOEXEC), or -1 with errno: ELOOP for a symbolic
  // link at that name, EMLINK for a file with other hard links, EISDIR (or ENXIO) for
  // something other than a regular file. Allocates nothing.
  int Create(const char* name) const;
  // Throws InputError when `name` is a symbolic link, or names something other than a
  // regular file (or a folder, with `folder`), with a message naming the path; nothing
  // happens when it does not exist. Returns whether it exists.
  bool CheckNotLink(const char* name, bool folder = false) const;
  // Removes file `name` (the name itself, never what a link points to); false with errno.
  bool Remove(const char* name) const;
  // The message for a failed Create (errno `error`) of `name`: "cannot create PATH: ...",
  // for a link "PATH is a symbolic link; ...".
  std::string CreateError(const char* name, int error) const;
  bool is_open() const { return fd_ >= 0; }
  int fd() const { return fd_; }
  const std::string& path() const { return path_; }
  void Close();

 private:
  int fd_ = -1;
  std::string path_;
};

// A CSV table: header "t,<columns>", then one row per call, each value written as the
// shortest text that reads back as the same double (AppendShortest). Rows are collected in memory (a batch) and written to the file by Flush
// or FlushTogether, so that the file ends with a complete row: when a write fails (a full
// disk, a file size limit) the torn last row is cut off, and the writer accepts no more rows.
class CsvWriter {
 public:
  CsvWriter() = default;
  CsvWriter(const CsvWriter&) = delete;
  CsvWriter& operator=(const CsvWriter&) = delete;
  ~CsvWriter();

  // Creates file `name` of `folder` (OutputFolder::Create: a new, empty regular file, never
  // through a link) and writes the header. Throws InputError when it cannot.
  void Open(const OutputFolder& folder, const char* name, const std::vector<std::string>& columns);
  // Appends "t,values..." to the batch (no file access). Returns false once a write has failed.
  // `key` orders the rows for FlushTogether: the output time's sequence number, shared by
  // the tables written at that time (several rows may have the same key, non-decreasing);
  // -1: the row's own index in the table.
  bool WriteRow(double t, const std::vector<double>& values, long long key = -1);
  // Appends values.size() / width lines "t,lead...,values[i width .. (i + 1) width)" (long
  // format: several lines at one time) as one row of the batch: a flush keeps or cuts them
  // together, and rows() counts them as one.
  bool WriteRows(double t, const std::vector<double>& lead, const std::vector<double>& values,
                 std::size_t width, long long key = -1);
  // Reserves batch room for `bytes` (rows longer than the default reservation of 68 KiB).
  void Reserve(std::size_t bytes);
  // Writes the batch. Returns false on a write error (errno kept): the rows that reached the
  // file whole stay, a torn row is cut off, the rest of the batch is dropped.
  bool Flush();
  // Flushes tables written at the same output times (points.csv, joints.csv, contacts.csv,
  // ...) so that they end at the same one: after a write error in any of them, every one is
  // cut back to the rows whose key is below the key of the first row that did not reach the
  // file whole (the output times all of them hold whole), and none accepts more rows.
  // Returns nullptr, or the first writer whose write failed (errno kept).
  static const CsvWriter* FlushTogether(std::initializer_list<CsvWriter*> writers);
  // The same for the first n writers of an array.
  static const CsvWriter* FlushTogether(CsvWriter* const* writers, std::size_t n);
  // Flushes and closes. Returns false on a write error.
  bool Close();
  const std::string& path() const { return path_; }
  // Rows in the file (after the last flush) and the time of the last one (NaN: none).
  long rows() const { return rows_; }
  double last_time() const { return last_time_; }
  long long last_key() const { return last_key_; }  // of the last row in the file (-1: none)
  std::size_t batch_bytes() const { return batch_.size(); }
  bool failed() const { return failed_; }

 private:
  // Writes the batch; returns the number of its rows written whole (the file may end with a
  // torn row after them), sets failed_ on an error.
  std::size_t WriteBatch();
  long long NextKey(long long key) const {
    return key >= 0 ? key : rows_ + static_cast<long long>(row_ends_.size());
  }
  // Cuts the file to its rows before the batch plus the batch's first n rows, drops the batch.
  void KeepBatchRows(std::size_t n);

  int fd_ = -1;
  std::string path_;
  std::string batch_;                  // complete rows not yet written
  std::vector<std::size_t> row_ends_;  // end offset of each batch row in batch_
  std::vector<double> row_times_;      // t of each batch row
  std::vector<long long> row_keys_;    // key of each batch row (WriteRow)
  long long file_bytes_ = 0;           // bytes in the file before the batch
  long rows_ = 0;
  double last_time_ = std::numeric_limits<double>::quiet_NaN();
  long long last_key_ = -1;
  bool failed_ = false;
};

// Builds JSON text: objects, arrays, strings (escaped), numbers (AppendShortest; NaN and infinities
// become null), integers, booleans. Commas and indentation are inserted automatically.
class JsonWriter {
 public:
  JsonWriter& BeginObject();
  JsonWriter& EndObject();
  JsonWriter& BeginArray();
  JsonWriter& EndArray();
  JsonWriter& Key(std::string_view key);
  JsonWriter& String(std::string_view value);
  JsonWriter& Number(double value);
  JsonWriter& Int(long value);
  JsonWriter& Bool(bool value);
  JsonWriter& Null();
  // Key followed by a value, for brevity.
  JsonWriter& Field(std::string_view key, std::string_view value) { return Key(key).String(value); }
  JsonWriter& Field(std::string_view key, const char* value) { return Key(key).String(value); }
  JsonWriter& Field(std::string_view key, double value) { return Key(key).Number(value); }
  JsonWriter& Field(std::string_view key, int value) { return Key(key).Int(value); }
  JsonWriter& Field(std::string_view key, long value) { return Key(key).Int(value); }
  JsonWriter& Field(std::string_view key, bool value) { return Key(key).Bool(value); }
  // The text (with a final newline once the outermost value is closed).
  const std::string& str() const { return text_; }

 private:
  void BeforeValue();
  void Newline();
  std::string text_;
  std::vector<bool> first_;  // per open container: no element written yet
  bool after_key_ = false;
};

// JSON string literal contents: escapes quotes, backslashes and control characters.
std::string JsonEscape(std::string_view text);

// Replaces file `name` of `folder` by text through a temporary file (name + kTemporarySuffix,
// OutputFolder::Create) and a rename in the folder, so a reader never sees a partial file.
// When the temporary file cannot be written (a full disk) an existing regular file of that
// name is overwritten in place instead (never through a link). Returns false (errno kept) on
// failure.
bool WriteFileAtomically(const OutputFolder& folder, const char* name, const std::string& text);

}  // namespace screwfem
