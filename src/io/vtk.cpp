#include "screwfem/io/vtk.h"

#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "screwfem/assemble/assemble.h"
#include "screwfem/assemble/outputs.h"
#include "screwfem/io/writers.h"
#include "screwfem/model/errors.h"

namespace screwfem {

namespace {

// The drawn geometry of one state.
struct Geometry {
  struct Cell {
    std::vector<int> points;
    int rod = -1, body = -1, joint = -1;
  };
  std::vector<Vec3> position, velocity;
  std::vector<Mat3> frame;
  std::vector<int> point_joint;
  std::vector<Cell> verts, lines;

  int AddPoint(const Vec3& x, const Mat3& R, const Vec3& v, int joint = -1) {
    position.push_back(x);
    frame.push_back(R);
    velocity.push_back(v);
    point_joint.push_back(joint);
    return static_cast<int>(position.size()) - 1;
  }
};

Geometry BuildGeometry(const Model& model, const Data& data) {
  Geometry g;
  const auto node_point = [&](int node, const Vec3& p) {
    return node == kGround ? PointMotion{p, Vec3::Zero(), Vec3::Zero()}
                           : CalcNodePointMotion(model, data, node, p);
  };

  // Joints: a vertex at the joint frame H_A C_A H_J, moving with side B when it is a node.
  std::vector<std::vector<Vec3>> attachments(model.nodes.size());
  for (std::size_t jj = 0; jj < model.joints.size(); ++jj) {
    const Joint& j = model.joints[jj];
    const SE3 H = NodeFrame(data, j.node_a) * j.offset_a * JointRelativeFrame(model, data, static_cast<int>(jj));
    const PointMotion m = j.node_b != kGround ? node_point(j.node_b, j.offset_b.x)
                                              : node_point(j.node_a, j.offset_a.x);
    Geometry::Cell cell;
    cell.joint = static_cast<int>(jj);
    cell.points.push_back(g.AddPoint(H.x, H.R, m.velocity, static_cast<int>(jj)));
    g.verts.push_back(std::move(cell));
    if (j.node_a != kGround) attachments[static_cast<std::size_t>(j.node_a)].push_back(j.offset_a.x);
    if (j.node_b != kGround) attachments[static_cast<std::size_t>(j.node_b)].push_back(j.offset_b.x);
  }

  // Rods: polylines through their nodes.
  for (std::size_t r = 0; r < model.rods.size(); ++r) {
    Geometry::Cell cell;
    cell.rod = static_cast<int>(r);
    for (int node : model.rods[r].nodes) {
      const SE3& H = data.H[static_cast<std::size_t>(node)];
      cell.points.push_back(g.AddPoint(H.x, H.R, node_point(node, Vec3::Zero()).velocity));
    }
    g.lines.push_back(std::move(cell));
  }

  // Rigid bodies: segments from the node origin to the centre of mass and the attachments.
  for (std::size_t b = 0; b < model.bodies.size(); ++b) {
    const RigidBody& body = model.bodies[b];
    const SE3& H = data.H[static_cast<std::size_t>(body.node)];
    std::vector<Vec3> ends = attachments[static_cast<std::size_t>(body.node)];
    ends.push_back(body.com);
    const int origin = g.AddPoint(H.x, H.R, node_point(body.node, Vec3::Zero()).velocity);
    bool drawn = false;
    for (std::size_t e = 0; e < ends.size(); ++e) {
      const Vec3& p = ends[e];
      bool repeated = p.norm() <= 1e-12 * model.length_scale;
      for (std::size_t f = 0; f < e && !repeated; ++f)
        repeated = (ends[f] - p).norm() <= 1e-12 * model.length_scale;
      if (repeated) continue;
      Geometry::Cell cell;
      cell.body = static_cast<int>(b);
      cell.points = {origin, g.AddPoint(H.Act(p), H.R, node_point(body.node, p).velocity)};
      g.lines.push_back(std::move(cell));
      drawn = true;
    }
    if (!drawn) {  // a point mass: a vertex at its node
      Geometry::Cell cell;
      cell.body = static_cast<int>(b);
      cell.points = {origin};
      g.verts.push_back(std::move(cell));
    }
  }
  return g;
}

// The file is composed in memory (numbers through AppendNumber, the printf formats of the
// format strings noted) and written at once.
void AppendInt(std::string* text, long value) {
  char buf[24];
  text->append(buf, std::to_chars(buf, buf + sizeof buf, value).ptr);
}

void WriteCells(std::string* f, const char* tag, const std::vector<Geometry::Cell>& cells) {
  if (cells.empty()) return;
  *f += "      <";
  *f += tag;
  *f += ">\n        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
  for (const Geometry::Cell& c : cells) {
    *f += "         ";
    for (int p : c.points) {
      *f += ' ';
      AppendInt(f, p);
    }
    *f += '\n';
  }
  *f += "        </DataArray>\n        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n         ";
  long offset = 0;
  for (const Geometry::Cell& c : cells) {
    offset += static_cast<long>(c.points.size());
    *f += ' ';
    AppendInt(f, offset);
  }
  *f += "\n        </DataArray>\n      </";
  *f += tag;
  *f += ">\n";
}

void WriteVectors(std::string* f, const char* name, const std::vector<Vec3>& values) {
  *f += "        <DataArray type=\"Float64\" Name=\"";
  *f += name;
  *f += "\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (const Vec3& v : values) {  // "          %.10g %.10g %.10g\n"
    *f += "         ";
    for (int i = 0; i < 3; ++i) {
      *f += ' ';
      AppendNumber(f, v(i), 10);
    }
    *f += '\n';
  }
  *f += "        </DataArray>\n";
}

void WriteInts(std::string* f, const char* name, const std::vector<int>& values) {
  *f += "        <DataArray type=\"Int32\" Name=\"";
  *f += name;
  *f += "\" format=\"ascii\">\n         ";
  for (int v : values) {
    *f += ' ';
    AppendInt(f, v);
  }
  *f += "\n        </DataArray>\n";
}

bool WriteVtp(const std::string& path, const Geometry& g, double time) {
  std::string f;
  f.reserve(4096 + 160 * g.position.size());
  f += "<?xml version=\"1.0\"?>\n"
       "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
       "  <PolyData>\n"
       "    <FieldData>\n"
       "      <DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">\n";
  f += "        ";
  AppendNumber(&f, time, 17);
  f += "\n      </DataArray>\n    </FieldData>\n";
  f += "    <Piece NumberOfPoints=\"";
  AppendInt(&f, static_cast<long>(g.position.size()));
  f += "\" NumberOfVerts=\"";
  AppendInt(&f, static_cast<long>(g.verts.size()));
  f += "\" NumberOfLines=\"";
  AppendInt(&f, static_cast<long>(g.lines.size()));
  f += "\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">\n";

  f += "      <PointData Vectors=\"velocity\">\n";
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<Vec3> column(g.frame.size());
    for (std::size_t i = 0; i < g.frame.size(); ++i) column[i] = g.frame[i].col(axis);
    WriteVectors(&f, axis == 0 ? "frame_x" : axis == 1 ? "frame_y" : "frame_z", column);
  }
  WriteVectors(&f, "velocity", g.velocity);
  WriteInts(&f, "joint_id", g.point_joint);
  f += "      </PointData>\n";

  // Cell data in the order VTK stores the cells: vertices, then lines.
  f += "      <CellData Scalars=\"rod_id\">\n";
  std::vector<int> rod, body, joint;
  for (const auto* cells : {&g.verts, &g.lines})
    for (const Geometry::Cell& c : *cells) {
      rod.push_back(c.rod);
      body.push_back(c.body);
      joint.push_back(c.joint);
    }
  WriteInts(&f, "rod_id", rod);
  WriteInts(&f, "body_id", body);
  WriteInts(&f, "joint_id", joint);
  f += "      </CellData>\n";

  f += "      <Points>\n";
  WriteVectors(&f, "position", g.position);
  f += "      </Points>\n";
  WriteCells(&f, "Verts", g.verts);
  WriteCells(&f, "Lines", g.lines);
  f += "    </Piece>\n  </PolyData>\n</VTKFile>\n";

  std::FILE* file = std::fopen(path.c_str(), "w");
  if (!file) return false;
  const bool ok = std::fwrite(f.data(), 1, f.size(), file) == f.size() && !std::ferror(file);
  const int saved = errno;
  const bool closed = std::fclose(file) == 0;
  errno = saved;
  return ok && closed;
}

}  // namespace

void VtkWriter::Open(const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw InputError("cannot create directory " + dir + ": " + ec.message());
  dir_ = dir;
  frames_.clear();
}

bool VtkWriter::WriteFrame(const Model& model, const Data& data, double time) {
  char name[32];
  std::snprintf(name, sizeof name, "frame_%05d.vtp", frames());
  const std::string path = dir_ + "/" + name;
  if (!WriteVtp(path, BuildGeometry(model, data), time)) {
    const int saved = errno;
    std::remove(path.c_str());
    errno = saved;
    return false;
  }
  frames_.emplace_back(time, name);
  return true;
}

bool VtkWriter::WriteCollection() const {
  std::string text =
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
      "  <Collection>\n";
  char line[128];
  for (const auto& [time, file] : frames_) {
    std::snprintf(line, sizeof line, "    <DataSet timestep=\"%.17g\" group=\"\" part=\"0\" file=\"%s\"/>\n",
                  time, file.c_str());
    text += line;
  }
  text += "  </Collection>\n</VTKFile>\n";
  return WriteFileAtomically(dir_ + "/motion.pvd", text);
}

}  // namespace screwfem
