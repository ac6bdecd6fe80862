// ParaView output of a run: one PolyData file per recorded frame and a Collection file that
// lists them with their times.
//
// DIR/frame_NNNNN.vtp   the mechanism at one time (world frame, metres), every cell tagged with
// its kind (cell data `kind`, VtkCellKind below; a Threshold on it separates them in ParaView):
//   vertices   one per joint, at the joint frame's origin (side A), with its frame axes (kJoint);
//              one per rigid body without segments, at its node (kBodyPoint); one per contact
//              pair with an obstacle, at the shape's surface point (kContact), and one per
//              contact segment of the moving shapes (kPairContact), carrying the contact force;
//              one per sphere and box contact shape of a rigid body, at its centre with the
//              body's axes (kSphere, kBox); one per rigid body of positive mass, the box of its
//              inertia at its centre of mass with the principal axes (kInertiaBox); one per
//              plane and sphere obstacle at its point, z along a plane's normal (kPlane,
//              kObstacleSphere);
//   polylines  one per rod, through its nodes in order (kRod);
//   lines      per rigid body, from its node origin to its centre of mass and to every joint
//              attachment point on it (kBodySegment: a link between two joints is drawn between
//              them); one per capsule shape and capsule obstacle, between its ends (kCapsule,
//              kObstacleCapsule); per triangle of a mesh or height-field obstacle, a closed
//              polyline through its corners (kObstacleMesh, item_id the obstacle);
//   polylines  one per tendon, through its eyelets at their current positions (kTendon), and one
//              line per force element between its ends (kForceElement); on the ground the frame
//              axes are the world's;
//   polylines  one per pressure chamber (an actuator of type pressure), through the points of
//              its centroid, the offset (0, r2, r3) in the section frame of every rod node it
//              covers, with the section's axes (kChamber, item_id the actuator).
//   Point data: frame_x, frame_y, frame_z (axes of the node frame, the section frame on rods,
//               the joint frame at joints, a shape's or inertia box's axes), velocity [m/s],
//               contact_force [N] (the force on the shape at kContact and kPairContact points,
//               zero elsewhere and when the pair is not touching), joint_id (-1 except at
//               joints), radius [m] and half_size [m] (constant, below).
//   Cell data:  kind, item_id (the cell's index in its own table: the joint, rod, body, tendon,
//               force element, contact pair, contact segment, contact shape or obstacle),
//               rod_id, body_id (also on a body's shapes and inertia box), joint_id (-1 where
//               they do not apply), tension [N] (a tendon's tension, a force element's force,
//               positive pulling; zero on other cells).
//   Field data: TimeValue [s].
// The sizes (radius, and half_size along the point's frame axes x, y, z): on a rod's points the
// section (Section's outline: radius = half_size y = half_size z for a round section; a
// rectangle's half-diagonal and (0, width/2, height/2)), else the rod's contact radius, else 0
// (a section given by its stiffness only: no size known); a sphere's or a capsule's radius (and
// r, r, r); a box's half-diagonal and half sizes; an inertia box's: the solid box of the body's
// mass and principal moments (half sizes a_i with a_1^2 = 3 (I_2 + I_3 - I_1) / (2 m)); an
// obstacle sphere's or capsule's radius; a chamber's: the circle of its area, sqrt(A / pi) (and
// 0, r, r); zero elsewhere.
//   With rod fields (Open's rod_fields, outputs.rod_fields), point data strain and stress (6
//   components each: gamma1 gamma2 gamma3 kappa1 kappa2 kappa3 and n1 n2 n3 m1 m2 m3, section
//   components as in rod_fields.csv, CalcRodFieldRows): at a rod node the mean of its elements
//   on either side (at an end node, its element's), zero at the other points.
// DIR/motion.pvd         the Collection, written once (atomically) when the run ends, also
//                        when it is interrupted or fails: it lists exactly the complete frame
//                        files on disk. (Rewriting it after every frame made a run quadratic
//                        in its number of frames.)
//
// Encodings (VtkFormat, the scene key outputs.vtk_format):
//   binary  every array in one <AppendedData encoding="raw"> block after the XML: per array a
//           UInt64 byte count, then the values in the machine's byte order (byte_order says
//           which). Doubles are stored exactly. Raw appended rather than inline base64 (the
//           other binary encoding VTK and ParaView read; docs/user-guide.md, "ParaView
//           frames", has the measurements): base64 takes 4/3 of the bytes of the arrays and must be encoded
//           on every frame, raw data is the arrays' memory itself; and since every array's
//           size is fixed by the model, the whole file (XML, offsets, connectivity, ids) is
//           composed once at Open and a frame only copies its doubles into it. What raw data
//           costs: the file is not well-formed XML (readers must cut the block out before
//           parsing, as VTK and tools/screwfem_vtk.py do).
//   ascii   the same arrays as text inside the XML (format="ascii"), each double the shortest
//           text that reads back as the same value; for reading with a text editor or diff.
#pragma once

#include <array>
#include <cstddef>
#include <initializer_list>
#include <string>
#include <vector>

#include "screwfem/io/scene.h"
#include "screwfem/io/writers.h"
#include "screwfem/model/data.h"

namespace screwfem {

// The cell data `kind` of the frames (values fixed: readers such as tools/screwfem_vtk.py and
// ParaView thresholds use the numbers).
enum class VtkCellKind : int {
  kJoint = 0,
  kRod = 1,
  kBodySegment = 2,
  kBodyPoint = 3,
  kTendon = 4,
  kForceElement = 5,
  kContact = 6,
  kPairContact = 7,
  kSphere = 8,
  kCapsule = 9,
  kBox = 10,
  kInertiaBox = 11,
  kPlane = 12,
  kObstacleSphere = 13,
  kObstacleCapsule = 14,
  kChamber = 15,
  kCylinder = 16,
  kObstacleCylinder = 17,
  kObstacleBox = 18,
  kObstacleMesh = 19,
};

class VtkWriter {
 public:
  // Creates the directory if needed (throws InputError if it cannot; an empty `dir`: none, for
  // frames only composed in memory by ComposeFrame) and lays out the frames
  // of `model`: which point each node, joint and body segment becomes, the cells and their
  // ids, and (binary) the whole file but its doubles. Reserves room for `expected_frames`
  // frames, so that writing up to that many allocates nothing.
  void Open(const std::string& dir, const Model& model, VtkFormat format = VtkFormat::kBinary,
            int expected_frames = 0, bool rod_fields = false);
  // The same in the subfolder kVtkFolder of a run's output folder (writers.h, OutputFolder):
  // created if needed, refused (InputError naming the path) when it is a symbolic link; the
  // frames and the collection are created in it by its descriptor, never through a link.
  void Open(const OutputFolder& parent, const Model& model, VtkFormat format = VtkFormat::kBinary,
            int expected_frames = 0, bool rod_fields = false);
  // Writes the next frame of data's current state at `time` (data of the model given to Open;
  // `load_factor` scales the rods' actuation in the rod fields and the tendons' tensions and
  // force elements' actuators, as in statics).
  // Returns false on a write error (errno kept; the incomplete frame file is removed and not
  // counted). Allocates no memory (binary, or ascii once its text buffer has grown to a
  // frame's size) while the frames fit the reserved count.
  bool WriteFrame(const Model& model, const Data& data, double time, double load_factor = 1.0);
  // The bytes of the frame WriteFrame would write next, composed in memory and not written
  // (nor counted): the live view of Python's Simulation.view reads them. The reference stays
  // valid until the next ComposeFrame or WriteFrame.
  const std::string& ComposeFrame(const Model& model, const Data& data, double time,
                                  double load_factor = 1.0);
  // Writes motion.pvd listing the frames written so far. Returns false on a write error.
  bool WriteCollection() const;
  int frames() const { return static_cast<int>(times_.size()); }
  const std::string& dir() const { return folder_.path(); }
  VtkFormat format() const { return format_; }

 private:
  // Where a point of the frame comes from.
  struct PointSource {
    // kSection: a tendon eyelet between rod nodes, on the section at xi of element `index`.
    // kPairContact: a contact segment (Model::contact_segments) of the moving shapes
    enum class Kind { kJoint, kNode, kWorld, kContact, kSection, kPairContact } kind = Kind::kNode;
    int index = -1;   // joint index (kJoint), node index (kNode), contact pair index (kContact,
                      // kPairContact: a contact segment), element (kSection)
    double xi = 0.0;  // kSection
    Vec3 offset = Vec3::Zero();  // kNode: point in the node frame [m]; kWorld: world point
    bool origin = true;          // kNode: the node frame's origin itself
    // kNode, kWorld when `rotated`: the point's axes in the node frame (the world's); the
    // frame axes written are then R axes.
    bool rotated = false;
    Mat3 axes = Mat3::Identity();
  };
  // The constant data of one cell.
  struct CellInfo {
    VtkCellKind kind = VtkCellKind::kJoint;
    int item = -1, rod = -1, body = -1, joint = -1;
  };
  void LayOut(const Model& model);
  void LayOutBodies(const Model& model, const std::vector<std::vector<Vec3>>& attachments);
  void LayOutLines(const Model& model);
  void LayOutMesh(const ContactObstacle& o, int id);
  void LayOutContact(const Model& model);
  void LayOutChambers(const Model& model);
  long long AddPoint(const PointSource& source, double radius = 0.0,
                     const Vec3& half_size = Vec3::Zero(), int joint = -1);
  void AddVertex(long long point, const CellInfo& cell);
  void AddLine(std::initializer_list<long long> points, const CellInfo& cell);
  // Closes a polyline of the points appended to line_connectivity_ since the last line.
  void EndLine(const CellInfo& cell);
  void CalcPoints(const Model& model, const Data& data, double load_factor);
  void ComposeBinaryImage();
  void ComposeAsciiImage(double time);
  bool WriteImage();

  void Prepare(const Model& model, VtkFormat format, int expected_frames, bool rod_fields);
  OutputFolder folder_;  // the frames' folder, open
  std::string name_;     // the frame file being written (capacity kept)
  VtkFormat format_ = VtkFormat::kBinary;
  std::vector<PointSource> sources_;
  // Cells (constant): vertices then lines, as VTK stores them; their data in that order.
  std::vector<long long> vert_connectivity_, vert_offsets_, line_connectivity_, line_offsets_;
  std::vector<CellInfo> vert_cells_, line_cells_;
  std::vector<int> point_joint_, cell_kind_, cell_item_, cell_rod_, cell_body_, cell_joint_;
  // Constant point sizes: radius (1 per point) and half sizes (3 per point).
  std::vector<double> radius_, half_size_;
  // Per-frame values, 3 per point.
  std::vector<double> frame_axes_[3], velocity_, position_;
  // Per-frame cell values: the tension of tendon and force element cells (zero elsewhere).
  std::vector<double> tension_;
  // The contact force on the shape at each contact pair's point (zero elsewhere and when the
  // pair is inactive), for glyphs.
  std::vector<double> contact_force_;
  // Per contact segment, filled at each frame from the pairs the broad phase found: the sum of
  // the contact forces on it, and of its contact points weighted by |F| (and the weights).
  std::vector<Vec3> segment_force_, segment_point_;
  std::vector<double> segment_weight_;
  // With contact: the state of each contact point (docs/numerics.md, "Stick friction"), 3 per
  // point: slipping (1) or sticking (0), the anchor's deflection [m] and the share of static
  // friction used (zero elsewhere); per contact segment the same over its active pairs (slip
  // if any slips, the largest deflection and share).
  std::vector<double> contact_state_;
  std::vector<Vec3> segment_state_;
  // The file: binary, composed at Open, with the byte offsets of the per-frame values;
  // ascii, recomposed per frame in the same buffer.
  std::string image_;
  std::size_t time_at_ = 0, frame_axes_at_[3] = {0, 0, 0}, velocity_at_ = 0, position_at_ = 0,
              contact_force_at_ = 0, contact_state_at_ = 0, tension_at_ = 0;
  std::vector<double> times_;  // of the frames written, frame i in frame_<i>.vtp

  // Rod fields (Open's rod_fields): per rod node point, the point and its two stations
  // (CalcRodFieldRows' rows), the rows of a frame, and the per-point strain and stress.
  void LayOutRodFields(const Model& model);
  void CalcRodFields(const Model& model, const Data& data, double load_factor);
  bool rod_fields_ = false;
  std::vector<std::array<long long, 3>> rod_points_;
  std::vector<double> field_rows_, strain_, stress_;
  std::size_t strain_at_ = 0, stress_at_ = 0;
};

}  // namespace screwfem
