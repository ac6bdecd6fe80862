#include "screwfem/io/writers.h"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>

#include "screwfem/assemble/assemble.h"
#include "screwfem/assemble/outputs.h"
#include "screwfem/model/errors.h"

namespace screwfem {

// ---- recorded quantities ---------------------------------------------------------------------

void ValidateOutputs(const Model& model, const OutputSpec& outputs) {
  const auto fail = [](const std::string& what, const std::string& name, const std::string& why) {
    throw InputError("outputs." + what + " '" + name + "': " + why);
  };
  for (const OutputPoint& p : outputs.points) {
    if (p.name.empty()) fail("points", p.name, "a recorded point needs a name");
    if (p.rod >= 0) {
      if (p.rod >= static_cast<int>(model.rods.size()))
        fail("points", p.name, "rod index " + std::to_string(p.rod) + " does not exist");
      const double length = model.rods[static_cast<std::size_t>(p.rod)].length;
      if (!(p.arc_length >= 0.0 && p.arc_length <= length * (1.0 + 1e-12)))
        fail("points", p.name,
             "arc length " + std::to_string(p.arc_length) + " m is outside the rod [0, " +
                 std::to_string(length) + "] m");
    } else if (p.node < 0 || p.node >= static_cast<int>(model.nodes.size())) {
      fail("points", p.name, "needs an existing node or rod");
    } else if (!p.offset.allFinite()) {
      fail("points", p.name, "offset is not finite");
    }
  }
  for (const OutputJoint& j : outputs.joints) {
    if (j.name.empty()) fail("joints", j.name, "a recorded joint needs a name");
    if (j.joint < 0 || j.joint >= static_cast<int>(model.joints.size()))
      fail("joints", j.name, "joint index " + std::to_string(j.joint) + " does not exist");
  }
}

std::vector<std::string> PointColumns(const std::vector<OutputPoint>& points) {
  static constexpr const char* kSuffix[9] = {"x", "y", "z", "vx", "vy", "vz", "ax", "ay", "az"};
  std::vector<std::string> columns;
  for (const OutputPoint& p : points)
    for (const char* s : kSuffix) columns.push_back(p.name + "." + s);
  return columns;
}

std::vector<std::string> JointColumns(const Model& model, const std::vector<OutputJoint>& joints) {
  static constexpr const char* kSuffix[4] = {"q", "qd", "qdd", "effort"};
  std::vector<std::string> columns;
  for (const OutputJoint& oj : joints) {
    const int k = model.joints[static_cast<std::size_t>(oj.joint)].k();
    for (int c = 0; c < k; ++c) {
      const std::string prefix = k == 1 ? oj.name + "." : oj.name + "." + std::to_string(c) + ".";
      for (const char* s : kSuffix) columns.push_back(prefix + s);
    }
  }
  return columns;
}

std::string JointsDescriptionJson(const Model& model, const std::vector<OutputJoint>& joints) {
  const auto drive_name = [](DriveKind d) {
    switch (d) {
      case DriveKind::kNone: return "none";
      case DriveKind::kPrescribed: return "prescribed";
      case DriveKind::kSeriesElastic: return "series_elastic";
      case DriveKind::kForce: return "force";
    }
    return "none";
  };
  JsonWriter w;
  const auto null_field = [&w](const char* key) { w.Key(key).Number(std::nan("")); };  // null
  w.BeginObject().Field("format", "screwfem joints 1").Key("joints").BeginArray();
  for (std::size_t jj = 0; jj < model.joints.size(); ++jj) {
    const Joint& j = model.joints[jj];
    const OutputJoint* recorded = nullptr;
    for (const OutputJoint& oj : joints)
      if (oj.joint == static_cast<int>(jj) && !recorded) recorded = &oj;
    w.BeginObject().Field("name", j.name).Field("index", static_cast<long>(jj));
    w.Field("type", JointTypeName(j.type)).Field("drive", drive_name(j.drive));
    if (j.drive != DriveKind::kNone)
      w.Field("drive_coordinate", j.drive_coord);
    else
      null_field("drive_coordinate");
    if (recorded)
      w.Field("column", recorded->name);
    else
      null_field("column");
    w.Key("coordinates").BeginArray();
    for (int c = 0; c < j.k(); ++c) {
      const bool angle = j.basis.col(c).tail<3>().squaredNorm() > 0.0;
      w.BeginObject();
      if (recorded)
        w.Field("column", j.k() == 1 ? recorded->name : recorded->name + "." + std::to_string(c));
      else
        null_field("column");
      w.Field("quantity", angle ? "angle" : "slide").Field("unit", angle ? "rad" : "m");
      w.Field("rate_unit", angle ? "rad/s" : "m/s").Field("acceleration_unit", angle ? "rad/s²" : "m/s²");
      w.Field("effort_unit", angle ? "N m" : "N");
      w.EndObject();
    }
    w.EndArray().EndObject();
  }
  w.EndArray().EndObject();
  return w.str();
}

void CalcPointRow(const Model& model, const Data& data, const std::vector<OutputPoint>& points,
                  std::vector<double>* row) {
  row->resize(9 * points.size());
  double* out = row->data();
  for (const OutputPoint& p : points) {
    const PointMotion m = p.rod >= 0 ? CalcRodPointMotion(model, data, p.rod, p.arc_length).motion
                                     : CalcNodePointMotion(model, data, p.node, p.offset);
    for (const Vec3* v : {&m.position, &m.velocity, &m.acceleration})
      for (int i = 0; i < 3; ++i) *out++ = (*v)(i);
  }
}

void CalcJointRow(const Model& model, const Data& data, const std::vector<OutputJoint>& joints,
                  std::vector<double>* row) {
  std::size_t n = 0;
  for (const OutputJoint& oj : joints)
    n += 4 * static_cast<std::size_t>(model.joints[static_cast<std::size_t>(oj.joint)].k());
  row->resize(n);
  double* out = row->data();
  for (const OutputJoint& oj : joints) {
    const Joint& j = model.joints[static_cast<std::size_t>(oj.joint)];
    for (int c = 0; c < j.k(); ++c) {
      const int dof = j.coord + c;
      *out++ = data.q_joint(dof - model.nv_nodes);
      *out++ = data.v(dof);
      *out++ = data.vdot(dof);
      *out++ = JointCoordinateEffort(model, data, oj.joint, c);
    }
  }
}

double JointCoordinateEffort(const Model& model, const Data& data, int joint, int c) {
  const Joint& j = model.joints[static_cast<std::size_t>(joint)];
  if (j.drive != DriveKind::kNone && c == j.drive_coord) return JointDriveEffort(model, data, joint);
  const double K = j.stiffness(c), D = j.damping(c);
  if (K == 0.0 && D == 0.0) return 0.0;
  const int dof = j.coord + c;
  const double damper = D * data.v(dof);
  if (JointHasGlobalCoordinates(j.type))
    return -(K * (data.q_joint(dof - model.nv_nodes) - j.rest(c)) + damper);
  // Group joints: energy 1/2 delta^T K delta with delta = A^T log(H_J); its gradient with
  // respect to the coordinates is A^T T^-T(xi) A K delta (method.md §4.5, as in the assembly).
  const int k = j.k();
  const Vec6 xi = LogSE3(data.HJ[static_cast<std::size_t>(joint)]);
  Vec6 k_delta_alg = Vec6::Zero();
  for (int i = 0; i < k; ++i) k_delta_alg += j.basis.col(i) * (j.stiffness(i) * j.basis.col(i).dot(xi));
  const double spring = j.basis.col(c).dot(TSE3Inv(xi).transpose() * k_delta_alg);
  return -(spring + damper);
}

// ---- CSV ---------------------------------------------------------------------------------------

void AppendNumber(std::string* text, double value, int precision) {
  char buf[64];
  const std::to_chars_result r =
      std::to_chars(buf, buf + sizeof buf, value, std::chars_format::general, precision);
  text->append(buf, r.ptr);
}

namespace {
constexpr std::size_t kCsvBufferBytes = 64 * 1024;  // rows collected before a write
}  // namespace

CsvWriter::~CsvWriter() { Close(); }

void CsvWriter::Open(const std::string& path, const std::vector<std::string>& columns) {
  Close();
  file_ = std::fopen(path.c_str(), "w");
  if (!file_) throw InputError("cannot create " + path + ": " + std::strerror(errno));
  path_ = path;
  rows_ = 0;
  pending_.clear();
  pending_.reserve(kCsvBufferBytes + 4096);
  std::fputs("t", file_);
  for (const std::string& c : columns) {
    std::fputc(',', file_);
    std::fputs(c.c_str(), file_);
  }
  std::fputc('\n', file_);
  if (std::fflush(file_) != 0 || std::ferror(file_))
    throw InputError("cannot write " + path + ": " + std::strerror(errno));
}

bool CsvWriter::WriteRow(double t, const std::vector<double>& values) {
  if (!file_) return false;
  AppendNumber(&pending_, t, 17);
  for (double v : values) {
    pending_ += ',';
    AppendNumber(&pending_, v, 17);
  }
  pending_ += '\n';
  ++rows_;
  return pending_.size() < kCsvBufferBytes || Flush();
}

bool CsvWriter::Flush() {
  if (!file_) return false;
  const bool written = pending_.empty() ||
                       std::fwrite(pending_.data(), 1, pending_.size(), file_) == pending_.size();
  pending_.clear();
  return written && std::fflush(file_) == 0 && !std::ferror(file_);
}

bool CsvWriter::Close() {
  if (!file_) return true;
  const bool flushed = Flush();
  const bool closed = std::fclose(file_) == 0;
  file_ = nullptr;
  return flushed && closed;
}

// ---- JSON --------------------------------------------------------------------------------------

std::string JsonEscape(std::string_view text) {
  std::string out;
  out.reserve(text.size() + 2);
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    switch (ch) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\r': out += "\\r"; break;
      case '\t': out += "\\t"; break;
      case '\b': out += "\\b"; break;
      case '\f': out += "\\f"; break;
      default:
        if (c < 0x20 || c == 0x7f) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", static_cast<unsigned>(c));
          out += buf;
        } else {
          out += ch;  // UTF-8 passes through unchanged
        }
    }
  }
  return out;
}

void JsonWriter::Newline() {
  text_ += '\n';
  text_.append(2 * first_.size(), ' ');
}

void JsonWriter::BeforeValue() {
  if (after_key_) {
    after_key_ = false;
    return;
  }
  if (!first_.empty()) {
    if (!first_.back()) text_ += ',';
    first_.back() = false;
    Newline();
  }
}

JsonWriter& JsonWriter::BeginObject() {
  BeforeValue();
  text_ += '{';
  first_.push_back(true);
  return *this;
}

JsonWriter& JsonWriter::EndObject() {
  const bool empty = first_.back();
  first_.pop_back();
  if (!empty) Newline();
  text_ += '}';
  if (first_.empty()) text_ += '\n';
  return *this;
}

JsonWriter& JsonWriter::BeginArray() {
  BeforeValue();
  text_ += '[';
  first_.push_back(true);
  return *this;
}

JsonWriter& JsonWriter::EndArray() {
  const bool empty = first_.back();
  first_.pop_back();
  if (!empty) Newline();
  text_ += ']';
  if (first_.empty()) text_ += '\n';
  return *this;
}

JsonWriter& JsonWriter::Key(std::string_view key) {
  BeforeValue();
  text_ += '"';
  text_ += JsonEscape(key);
  text_ += "\": ";
  after_key_ = true;
  return *this;
}

JsonWriter& JsonWriter::String(std::string_view value) {
  BeforeValue();
  text_ += '"';
  text_ += JsonEscape(value);
  text_ += '"';
  return *this;
}

JsonWriter& JsonWriter::Number(double value) {
  BeforeValue();
  if (!std::isfinite(value)) {
    text_ += "null";
    return *this;
  }
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", value);
  text_ += buf;
  return *this;
}

JsonWriter& JsonWriter::Int(long value) {
  BeforeValue();
  text_ += std::to_string(value);
  return *this;
}

JsonWriter& JsonWriter::Bool(bool value) {
  BeforeValue();
  text_ += value ? "true" : "false";
  return *this;
}

// ---- files -------------------------------------------------------------------------------------

bool WriteFileAtomically(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  std::FILE* f = std::fopen(tmp.c_str(), "w");
  if (!f) return false;
  const bool written = std::fwrite(text.data(), 1, text.size(), f) == text.size();
  const bool closed = std::fclose(f) == 0;
  if (!written || !closed) {
    const int saved = errno;
    std::remove(tmp.c_str());
    errno = saved;
    return false;
  }
  return std::rename(tmp.c_str(), path.c_str()) == 0;
}

}  // namespace screwfem
