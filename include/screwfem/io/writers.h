// Result tables and the run summary (see run.h for the files): the columns and values of
// points.csv and joints.csv, a CSV writer that writes whole rows, a small JSON text builder
// and an atomic file replacement.
#pragma once

#include <cstdio>
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

// Column names after "t": per point P: P.x P.y P.z P.vx P.vy P.vz P.ax P.ay P.az.
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
// [m], velocity [m/s] and acceleration [m/s^2] (method.md §6); joint coordinates [m or rad]
// and their first and second time derivatives, and the effort [N or N m].
// `row` is resized to the number of columns (no allocation once it has that size).
void CalcPointRow(const Model& model, const Data& data, const std::vector<OutputPoint>& points,
                  std::vector<double>* row);
void CalcJointRow(const Model& model, const Data& data, const std::vector<OutputJoint>& joints,
                  std::vector<double>* row);

// Generalised force acting on coordinate c of a joint [N or N m]: the drive's effort
// (JointDriveEffort) on the driven coordinate, otherwise the force of the joint's spring and
// damper on the coordinate, -(K (alpha - rest) + D alpha_dot) (method.md §4.5; for spherical,
// planar and free joints the spring acts on log(H_J) as in the assembly), otherwise 0.
double JointCoordinateEffort(const Model& model, const Data& data, int joint, int c);

// ---- files -----------------------------------------------------------------------------------

// Appends `value` formatted as printf("%.*g", precision, value) would (std::to_chars with a
// precision is specified to match printf, and is several times faster).
void AppendNumber(std::string* text, double value, int precision);

// A CSV table: header "t,<columns>", then one row per call, each written with full double
// precision (%.17g). Rows are collected and written to the file whole, when 64 KiB have
// accumulated and on Flush() and Close(), so that the file always ends with a complete line.
class CsvWriter {
 public:
  CsvWriter() = default;
  CsvWriter(const CsvWriter&) = delete;
  CsvWriter& operator=(const CsvWriter&) = delete;
  ~CsvWriter();

  // Creates (truncates) the file and writes the header. Throws InputError when it cannot.
  void Open(const std::string& path, const std::vector<std::string>& columns);
  // Appends "t,values..." (to the file once enough rows have accumulated). Returns false on a
  // write error (errno is kept).
  bool WriteRow(double t, const std::vector<double>& values);
  // Writes the collected rows to the file and flushes it. Returns false on a write error.
  bool Flush();
  // Flushes and closes. Returns false on a write error.
  bool Close();
  const std::string& path() const { return path_; }
  long rows() const { return rows_; }

 private:
  std::FILE* file_ = nullptr;
  std::string path_;
  std::string pending_;  // complete rows not yet written
  long rows_ = 0;
};

// Builds JSON text: objects, arrays, strings (escaped), numbers (%.17g; NaN and infinities
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

// Replaces the file at path by text through a temporary file in the same directory and a
// rename, so a reader never sees a partial file. Returns false (errno kept) on failure.
bool WriteFileAtomically(const std::string& path, const std::string& text);

}  // namespace screwfem
