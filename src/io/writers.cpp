#include "screwfem/io/writers.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <span>
#include <stdexcept>

#include "screwfem/assemble/assemble.h"
#include "screwfem/assemble/outputs.h"
#include "screwfem/elements/rod.h"
#include "screwfem/elements/contact.h"
#include "screwfem/elements/shape_pair.h"
#include "screwfem/elements/tendon.h"
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
  static constexpr const char* kSuffix[13] = {"x",  "y",  "z",  "vx", "vy", "vz", "ax",
                                              "ay", "az", "qw", "qx", "qy", "qz"};
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

std::vector<std::string> ReactionColumns(const Model& model) {
  static constexpr const char* kSuffix[6] = {"Fx", "Fy", "Fz", "Mx", "My", "Mz"};
  std::vector<std::string> columns;
  for (std::size_t jj = 0; jj < model.joints.size(); ++jj) {
    const Joint& j = model.joints[jj];
    if (j.row < 0) continue;
    std::string name = j.name;
    if (name.empty()) name.append("J").append(std::to_string(jj));
    for (const char* s : kSuffix) columns.push_back(name + "." + s);
  }
  return columns;
}

void CalcReactionRow(const Model& model, const Data& data, std::vector<double>* row) {
  std::size_t n = 0;
  for (const Joint& j : model.joints)
    if (j.row >= 0) n += 6;
  row->resize(n);
  std::size_t i = 0;
  for (std::size_t jj = 0; jj < model.joints.size(); ++jj) {
    if (model.joints[jj].row < 0) continue;
    const Vec6 r = CalcJointReaction(model, data, static_cast<int>(jj));
    for (int c = 0; c < 6; ++c) (*row)[i++] = r(c);
  }
}

std::vector<std::string> RodFieldColumns() {
  return {"rod",    "s",  "gamma1", "gamma2", "gamma3", "kappa1", "kappa2",
          "kappa3", "n1", "n2",     "n3",     "m1",     "m2",     "m3"};
}

std::vector<std::string> SettlingColumns() {
  return {"kinetic", "speed", "angular_speed", "contacts", "slipping", "overlap", "overlap_ratio"};
}

void CalcSettlingRow(const Model& model, const Data& data, bool dynamics, double kinetic,
                     std::vector<double>* row) {
  const SettlingState s = CalcSettlingState(model, data, dynamics, kinetic);
  row->resize(7);
  double* r = row->data();
  r[0] = s.kinetic;
  r[1] = s.speed;
  r[2] = s.angular_speed;
  r[3] = s.contacts;
  r[4] = s.slipping;
  r[5] = s.overlap;
  r[6] = s.overlap_ratio;
}

std::vector<std::string> EnergyColumns() {
  return {"kinetic", "strain", "spring", "gravity", "total", "px", "py", "pz", "Lx", "Ly", "Lz"};
}

void CalcEnergyRow(const Model& model, const Data& data, std::vector<double>* row) {
  const Energy e = CalcEnergy(model, data);  // with the momentum, in one pass
  const Vec6& h = e.momentum;
  row->resize(11);
  double* r = row->data();
  r[0] = e.kinetic;
  r[1] = e.strain;
  r[2] = e.spring;
  r[3] = e.gravity;
  r[4] = e.total();
  for (int c = 0; c < 6; ++c) r[5 + c] = h(c);
}

std::string JointsDescriptionJson(const Model& model, const std::vector<OutputJoint>& joints) {
  JsonWriter w;
  const auto null_field = [&w](const char* key) { w.Key(key).Number(std::nan("")); };  // null
  w.BeginObject().Field("format", "screwfem joints 1").Key("joints").BeginArray();
  for (std::size_t jj = 0; jj < model.joints.size(); ++jj) {
    const Joint& j = model.joints[jj];
    const OutputJoint* recorded = nullptr;
    for (const OutputJoint& oj : joints)
      if (oj.joint == static_cast<int>(jj) && !recorded) recorded = &oj;
    w.BeginObject().Field("name", j.name).Field("index", static_cast<long>(jj));
    w.Field("type", JointTypeName(j.type)).Field("drive", NameOf(j.drive));
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
      w.Field("rate_unit", angle ? "rad/s" : "m/s")
          .Field("acceleration_unit", angle ? "rad/s²" : "m/s²");
      w.Field("effort_unit", angle ? "N m" : "N");
      w.EndObject();
    }
    w.EndArray().EndObject();
  }
  w.EndArray().EndObject();
  return w.str();
}

Eigen::Vector4d FrameQuaternion(const Mat3& R) {
  Eigen::Quaterniond q(R);
  q.normalize();
  Eigen::Vector4d out(q.w(), q.x(), q.y(), q.z());
  // q and -q are the same rotation: w >= 0, and at w = 0 the first non-zero of x, y, z > 0.
  int lead = 0;
  while (lead < 3 && out(lead) == 0.0) ++lead;
  if (out(lead) < 0.0) out = -out;
  return out;
}

void CalcPointRow(const Model& model, const Data& data, const std::vector<OutputPoint>& points,
                  std::vector<double>* row) {
  row->resize(kPointColumns * points.size());
  double* out = row->data();
  for (const OutputPoint& p : points) {
    PointMotion m;
    Eigen::Vector4d q;
    if (p.rod >= 0) {
      const RodPoint r = CalcRodPointMotion(model, data, p.rod, p.arc_length);
      m = r.motion;
      q = FrameQuaternion(r.frame.R);
    } else {
      m = CalcNodePointMotion(model, data, p.node, p.offset);
      q = FrameQuaternion(data.H[static_cast<std::size_t>(p.node)].R);
    }
    for (const Vec3* v : {&m.position, &m.velocity, &m.acceleration})
      for (int i = 0; i < 3; ++i) *out++ = (*v)(i);
    for (int i = 0; i < 4; ++i) *out++ = q(i);
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

namespace {

template <typename Items>
std::vector<std::string> LineColumns(const Items& items, const char* force) {
  std::vector<std::string> columns;
  for (const auto& item : items)
    for (const char* q : {".length", ".rate", force}) columns.push_back(item.name + q);
  return columns;
}

template <typename State>
void CalcLineRow(std::size_t count, State&& state, std::vector<double>* row) {
  row->resize(3 * count);
  for (std::size_t i = 0; i < count; ++i) {
    const LineForceState s = state(static_cast<int>(i));
    (*row)[3 * i] = s.length;
    (*row)[3 * i + 1] = s.rate;
    (*row)[3 * i + 2] = s.force;
  }
}

}  // namespace

std::vector<std::string> TendonColumns(const Model& model) {
  return LineColumns(model.tendons, ".tension");
}

std::vector<std::string> ForceColumns(const Model& model) {
  return LineColumns(model.force_elements, ".force");
}

void CalcTendonRow(const Model& model, const Data& data, std::vector<double>* row,
                   double load_factor) {
  CalcLineRow(
      model.tendons.size(), [&](int i) { return CalcTendonState(model, data, i, load_factor); },
      row);
}

void CalcForceRow(const Model& model, const Data& data, std::vector<double>* row,
                  double load_factor) {
  CalcLineRow(
      model.force_elements.size(),
      [&](int i) { return CalcForceElementState(model, data, i, load_factor); }, row);
}

std::vector<std::string> ActuatorColumns(const Model& model) {
  std::vector<std::string> columns;
  for (const Actuator& a : model.actuators) columns.push_back(a.name);
  return columns;
}

void CalcActuatorRow(const Model& model, const Data& data, double t, std::vector<double>* row) {
  row->resize(model.actuators.size());
  for (std::size_t i = 0; i < model.actuators.size(); ++i)
    (*row)[i] = ActuatorValue(model.actuators[i], t, data);
}

std::vector<std::string> ContactColumns() {
  return {"pair", "rod", "owner", "obstacle", "px",  "py",  "pz",   "nx",         "ny",
          "nz",   "fn",  "ftx",   "fty",      "ftz", "gap", "slip", "deflection", "share"};
}

bool CalcContactRow(const Model& model, const Data& data, int pair, std::vector<double>* row) {
  row->resize(18);
  const ContactState c = CalcContactState(model, data, pair);
  if (!c.active) return false;
  const ContactPair& p = model.contact_pairs[static_cast<std::size_t>(pair)];
  double* r = row->data();
  r[0] = pair;
  r[1] = p.rod ? 1.0 : 0.0;
  r[2] = p.owner;
  r[3] = p.obstacle;
  for (int i = 0; i < 3; ++i) {
    r[4 + i] = c.point(i);
    r[7 + i] = c.normal(i);
    r[11 + i] = c.friction_force(i);
  }
  r[10] = c.normal_force;
  r[14] = c.gap;
  r[15] = c.slipping ? 1.0 : 0.0;  // stick law: 1 slipping, 0 sticking (smooth law: 0)
  r[16] = c.deflection;            // the anchor's elastic deflection [m] (stick law)
  r[17] = c.friction_share;        // |f_t| / (mu_s f_n)
  return true;
}

std::vector<std::string> PairContactColumns() {
  return {"pair", "rod_a", "owner_a", "element_a", "rod_b", "owner_b",    "element_b", "pax", "pay",
          "paz",  "pbx",   "pby",     "pbz",       "nx",    "ny",         "nz",        "fn",  "ftx",
          "fty",  "ftz",   "gap",     "part",      "slip",  "deflection", "share"};
}

bool CalcPairContactRow(const Model& model, const Data& data, int pair, std::vector<double>* row) {
  row->resize(25);
  const ShapePairState c = CalcShapePairState(model, data, pair);
  if (!c.active) return false;
  const ShapePair& p = data.shape_pairs[static_cast<std::size_t>(pair)];
  double* r = row->data();
  r[0] = ShapePairKey(model, p);
  for (int k = 0; k < 2; ++k) {
    r[1 + 3 * k] = p.side[k].rod ? 1.0 : 0.0;
    r[2 + 3 * k] = p.side[k].owner;
    r[3 + 3 * k] = p.side[k].element;
  }
  for (int i = 0; i < 3; ++i) {
    r[7 + i] = c.point[0](i);
    r[10 + i] = c.point[1](i);
    r[13 + i] = c.normal(i);
    r[17 + i] = c.friction_force(i);
  }
  r[16] = c.normal_force;
  r[20] = c.gap;
  r[21] = p.part;  // 0, 1: the clipped ends of a segment on a box; -1: one point
  r[22] = c.slipping ? 1.0 : 0.0;
  r[23] = c.deflection;
  r[24] = c.friction_share;
  return true;
}

// ---- CSV ---------------------------------------------------------------------------------------

void AppendNumber(std::string* text, double value, int precision) {
  char buf[64];
  const std::to_chars_result r =
      std::to_chars(buf, buf + sizeof buf, value, std::chars_format::general, precision);
  text->append(buf, r.ptr);
}

void AppendShortest(std::string* text, double value) {
  char buf[64];
  const std::to_chars_result r = std::to_chars(buf, buf + sizeof buf, value);
  text->append(buf, r.ptr);
}

namespace {

constexpr std::size_t kCsvBatchBytes = 64 * 1024;  // batch capacity reserved at Open

// write(2) until all of `size` bytes are written or an error; returns the bytes written.
std::size_t WriteAll(int fd, const char* data, std::size_t size) {
  std::size_t done = 0;
  while (done < size) {
    const ssize_t n = ::write(fd, data + done, size - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      if (n == 0) errno = EIO;
      break;
    }
    done += static_cast<std::size_t>(n);
  }
  return done;
}

}  // namespace

CsvWriter::~CsvWriter() { Close(); }

void CsvWriter::Open(const OutputFolder& folder, const char* name,
                     const std::vector<std::string>& columns) {
  Close();
  const std::string path = folder.path() + "/" + name;
  fd_ = folder.Create(name);
  if (fd_ < 0) throw InputError(folder.CreateError(name, errno));
  path_ = path;
  rows_ = 0;
  last_time_ = std::numeric_limits<double>::quiet_NaN();
  last_key_ = -1;
  failed_ = false;
  batch_.clear();
  batch_.reserve(kCsvBatchBytes + 4096);
  row_ends_.clear();
  row_ends_.reserve(4096);
  row_times_.clear();
  row_times_.reserve(4096);
  row_keys_.clear();
  row_keys_.reserve(4096);
  std::string header = "t";
  for (const std::string& c : columns) header += "," + c;
  header += '\n';
  if (WriteAll(fd_, header.data(), header.size()) != header.size())
    throw InputError("cannot write " + path + ": " + std::strerror(errno));
  file_bytes_ = static_cast<long long>(header.size());
}

namespace {

// The longest text std::to_chars gives a double without a precision
// ("-2.2250738585072014e-308"), and a comma.
constexpr std::size_t kMaxNumberChars = 25;

// The text of a row's time, kept for the next table's row at the same time (the tables of one
// output event share t): formatted once per event instead of once per table.
struct TimeText {
  std::uint64_t bits = 0;
  bool valid = false;
  std::size_t size = 0;
  char text[kMaxNumberChars] = {};
};
thread_local TimeText g_time_text;

// Writes t as AppendShortest would at `out`; returns the end.
char* WriteTime(char* out, double t) {
  std::uint64_t bits;
  std::memcpy(&bits, &t, sizeof bits);
  TimeText& c = g_time_text;
  if (!c.valid || c.bits != bits) {
    c.size =
        static_cast<std::size_t>(std::to_chars(c.text, c.text + sizeof c.text, t).ptr - c.text);
    c.bits = bits;
    c.valid = true;
  }
  std::memcpy(out, c.text, c.size);
  return out + c.size;
}

}  // namespace

bool CsvWriter::WriteRow(double t, const std::vector<double>& values, long long key) {
  if (fd_ < 0 || failed_) return false;
  row_keys_.push_back(NextKey(key));
  // The row is formatted in place, at the batch's end (room made first: no std::string
  // append per value), then the batch is cut to what was written: the same text as
  // AppendShortest value by value.
  const std::size_t start = batch_.size();
  batch_.resize(start + kMaxNumberChars * (values.size() + 1) + 1);
  char* const begin = batch_.data() + start;
  char* const end = batch_.data() + batch_.size();
  char* out = WriteTime(begin, t);
  for (double v : values) {
    *out++ = ',';
    out = std::to_chars(out, end, v).ptr;
  }
  *out++ = '\n';
  batch_.resize(start + static_cast<std::size_t>(out - begin));
  row_ends_.push_back(batch_.size());
  row_times_.push_back(t);
  return true;
}

bool CsvWriter::WriteRows(double t, const std::vector<double>& lead,
                          const std::vector<double>& values, std::size_t width, long long key) {
  if (fd_ < 0 || failed_) return false;
  row_keys_.push_back(NextKey(key));
  for (std::size_t i = 0; i + width <= values.size() && width > 0; i += width) {
    AppendShortest(&batch_, t);
    for (double v : lead) {
      batch_ += ',';
      AppendShortest(&batch_, v);
    }
    for (std::size_t k = i; k < i + width; ++k) {
      batch_ += ',';
      AppendShortest(&batch_, values[k]);
    }
    batch_ += '\n';
  }
  row_ends_.push_back(batch_.size());
  row_times_.push_back(t);
  return true;
}

void CsvWriter::Reserve(std::size_t bytes) { batch_.reserve(bytes); }

std::size_t CsvWriter::WriteBatch() {
  if (fd_ < 0 || failed_) return 0;
  const std::size_t written = WriteAll(fd_, batch_.data(), batch_.size());
  if (written == batch_.size()) return row_ends_.size();
  failed_ = true;
  return static_cast<std::size_t>(std::upper_bound(row_ends_.begin(), row_ends_.end(), written) -
                                  row_ends_.begin());
}

void CsvWriter::KeepBatchRows(std::size_t n) {
  n = std::min(n, row_ends_.size());
  const long long end = file_bytes_ + static_cast<long long>(n > 0 ? row_ends_[n - 1] : 0);
  if (failed_ || n < row_ends_.size()) {
    const int saved = errno;
    if (::ftruncate(fd_, static_cast<off_t>(end)) != 0) failed_ = true;
    ::lseek(fd_, static_cast<off_t>(end), SEEK_SET);
    errno = saved;
  }
  file_bytes_ = end;
  rows_ += static_cast<long>(n);
  if (n > 0) {
    last_time_ = row_times_[n - 1];
    last_key_ = row_keys_[n - 1];
  }
  batch_.clear();
  row_ends_.clear();
  row_times_.clear();
  row_keys_.clear();
}

bool CsvWriter::Flush() { return FlushTogether({this}) == nullptr; }

const CsvWriter* CsvWriter::FlushTogether(std::initializer_list<CsvWriter*> writers) {
  return FlushTogether(writers.begin(), writers.size());
}

const CsvWriter* CsvWriter::FlushTogether(CsvWriter* const* list, std::size_t n) {
  const std::span<CsvWriter* const> writers(list, n);
  // The key of the first row that did not reach its file whole, over the writers that
  // failed: every writer keeps its rows below it (the output times all of them hold whole).
  long long cut = std::numeric_limits<long long>::max();
  const CsvWriter* failed = nullptr;
  int failed_errno = 0;
  for (CsvWriter* w : writers) {
    const bool was_failed = w->failed_ || w->fd_ < 0;
    const std::size_t whole = w->WriteBatch();
    if ((w->failed_ || w->fd_ < 0) && failed == nullptr) {
      failed = w;
      failed_errno = was_failed ? EIO : errno;
    }
    if (w->failed_ && whole < w->row_keys_.size()) cut = std::min(cut, w->row_keys_[whole]);
  }
  for (CsvWriter* w : writers) {
    if (w->fd_ < 0) continue;
    if (failed != nullptr) w->failed_ = true;  // the tables stay at the same output time
    const std::size_t keep = static_cast<std::size_t>(
        std::lower_bound(w->row_keys_.begin(), w->row_keys_.end(), cut) - w->row_keys_.begin());
    w->KeepBatchRows(keep);
  }
  if (failed != nullptr) errno = failed_errno;
  return failed;
}

bool CsvWriter::Close() {
  if (fd_ < 0) return true;
  const bool flushed = batch_.empty() ? !failed_ : Flush();
  const bool closed = ::close(fd_) == 0;
  fd_ = -1;
  return flushed && closed;
}

// ---- JSON --------------------------------------------------------------------------------------

std::string JsonEscape(std::string_view text) {
  std::string out;
  out.reserve(text.size() + 2);
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    switch (ch) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\r':
        out += "\\r";
        break;
      case '\t':
        out += "\\t";
        break;
      case '\b':
        out += "\\b";
        break;
      case '\f':
        out += "\\f";
        break;
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
  AppendShortest(&text_, value);
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

JsonWriter& JsonWriter::Null() {
  BeforeValue();
  text_ += "null";
  return *this;
}

// ---- files -------------------------------------------------------------------------------------

bool IsFrameFileName(std::string_view name) {
  constexpr std::string_view head = "frame_", tail = ".vtp";
  if (name.size() < head.size() + 5 + tail.size() || name.substr(0, head.size()) != head ||
      name.substr(name.size() - tail.size()) != tail)
    return false;
  const std::string_view digits = name.substr(head.size(), name.size() - head.size() - tail.size());
  return std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; });
}

bool IsOutputFileName(std::string_view name, bool vtk) {
  if (vtk) {
    for (const char* f : kVtkFiles)
      if (name == f) return true;
    return IsFrameFileName(name);
  }
  for (const char* f : kOutputFiles)
    if (name == f) return true;
  return false;
}

OutputFolder::~OutputFolder() { Close(); }

void OutputFolder::Close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

void OutputFolder::Open(const std::string& path, bool create) {
  Close();
  if (create) {
    std::error_code ec;
    std::filesystem::create_directories(path, ec);
    if (ec) throw InputError("cannot create the output directory " + path + ": " + ec.message());
  }
  fd_ = ::open(path.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd_ < 0)
    throw InputError("cannot open the output directory " + path + ": " + std::strerror(errno));
  path_ = path;
}

void OutputFolder::OpenSubfolder(const OutputFolder& parent, const char* name, bool create) {
  Close();
  path_ = parent.path() + "/" + name;
  if (create && ::mkdirat(parent.fd(), name, 0777) != 0 && errno != EEXIST)
    throw InputError("cannot create directory " + path_ + ": " + std::strerror(errno));
  parent.CheckNotLink(name, true);
  fd_ = ::openat(parent.fd(), name, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
  if (fd_ < 0) {
    const int error = errno;
    if (error == ELOOP || error == ENOTDIR) parent.CheckNotLink(name, true);
    throw InputError("cannot open directory " + path_ + ": " + std::strerror(error));
  }
}

bool OutputFolder::CheckNotLink(const char* name, bool folder) const {
  struct stat st {};
  if (::fstatat(fd_, name, &st, AT_SYMLINK_NOFOLLOW) != 0) return false;
  const std::string path = path_ + "/" + name;
  if (S_ISLNK(st.st_mode))
    throw InputError(path +
                     " is a symbolic link; screwfem writes its files into the output directory "
                     "itself and never through a link: remove the link or choose another "
                     "output directory");
  if (folder ? !S_ISDIR(st.st_mode) : !S_ISREG(st.st_mode))
    throw InputError(path + " is not a " + (folder ? "directory" : "regular file") +
                     "; remove it or choose another output directory");
  return true;
}

int OutputFolder::Create(const char* name) const {
  const std::string_view n(name);
  const bool vtk = !IsOutputFileName(n, false);
  if (vtk && !IsOutputFileName(n, true))
    throw std::logic_error("OutputFolder::Create: '" + std::string(n) +
                           "' is not one of screwfem's output files (writers.h, kOutputFiles)");
  // No O_TRUNC before the checks: a hard link's other file must not be emptied. O_NONBLOCK:
  // a FIFO at the name fails (ENXIO) rather than blocking.
  const int fd =
      ::openat(fd_, name, O_WRONLY | O_CREAT | O_NOFOLLOW | O_CLOEXEC | O_NONBLOCK, 0666);
  if (fd < 0) return -1;
  struct stat st {};
  int error = 0;
  if (::fstat(fd, &st) != 0)
    error = errno;
  else if (!S_ISREG(st.st_mode))
    error = EISDIR;
  else if (st.st_nlink > 1)
    error = EMLINK;
  else if (::ftruncate(fd, 0) != 0 || ::fcntl(fd, F_SETFL, O_WRONLY) != 0)
    error = errno;
  if (error != 0) {
    ::close(fd);
    errno = error;
    return -1;
  }
  return fd;
}

bool OutputFolder::Remove(const char* name) const { return ::unlinkat(fd_, name, 0) == 0; }

std::string OutputFolder::CreateError(const char* name, int error) const {
  const std::string path = path_ + "/" + name;
  if (error == ELOOP)
    return path +
           " is a symbolic link; screwfem writes its files into the output directory itself "
           "and never through a link: remove the link or choose another output directory";
  if (error == EMLINK)
    return "cannot create " + path +
           ": it is a hard link of another file, which screwfem would overwrite; remove it or "
           "choose another output directory";
  if (error == EISDIR)
    return "cannot create " + path +
           ": it is not a regular file; remove it or choose another "
           "output directory";
  return "cannot create " + path + ": " + std::strerror(error);
}

bool WriteFileAtomically(const OutputFolder& folder, const char* name, const std::string& text) {
  const std::string tmp = std::string(name) + kTemporarySuffix;
  int fd = folder.Create(tmp.c_str());
  if (fd >= 0) {
    const bool written = WriteAll(fd, text.data(), text.size()) == text.size();
    int saved = errno;
    const bool closed = ::close(fd) == 0;
    if (!closed) saved = errno;
    if (written && closed && ::renameat(folder.fd(), tmp.c_str(), folder.fd(), name) == 0)
      return true;
    errno = saved;
  }
  // No room for a second copy (a full disk): overwrite the existing file in place, which
  // reuses its blocks (a summary is rewritten with about its earlier size); never through a
  // link (O_NOFOLLOW), only a regular file of its own.
  const int saved = errno;
  ::unlinkat(folder.fd(), tmp.c_str(), 0);
  fd = ::openat(folder.fd(), name, O_WRONLY | O_NOFOLLOW | O_CLOEXEC | O_NONBLOCK);
  struct stat st {};
  if (fd >= 0 && (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode) || st.st_nlink > 1)) {
    ::close(fd);
    fd = -1;
  }
  if (fd < 0) {
    errno = saved;
    return false;
  }
  const bool in_place = WriteAll(fd, text.data(), text.size()) == text.size() &&
                        ::ftruncate(fd, static_cast<off_t>(text.size())) == 0;
  const int in_place_errno = errno;
  ::close(fd);
  errno = in_place ? 0 : in_place_errno;
  return in_place;
}

}  // namespace screwfem
