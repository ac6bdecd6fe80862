// ParaView output of a run: one PolyData file per recorded frame and a Collection file that
// lists them with their times.
//
// DIR/frame_NNNNN.vtp   the mechanism at one time (world frame, metres):
//   vertices   one per joint, at the joint frame's origin (side A);
//   polylines  one per rod, through its nodes in order;
//   lines      per rigid body, from its node origin to its centre of mass and to every joint
//              attachment point on it (so a link between two joints is drawn between them);
//   polylines  one per tendon, through its eyelets, and one line per force element between its
//              ends (rod_id = body_id = joint_id = -1; on the ground the frame axes are the
//              world's).
//   Point data: frame_x, frame_y, frame_z (axes of the node frame, the section frame on rods,
//               the joint frame at joints), velocity [m/s], joint_id (-1 except at joints).
//   Cell data:  rod_id, body_id, joint_id (-1 where they do not apply).
//   Field data: TimeValue [s].
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
//           other binary encoding VTK and ParaView read; README.md, "ParaView frames", has the
//           measurements): base64 takes 4/3 of the bytes of the arrays and must be encoded
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
#include <string>
#include <vector>

#include "screwfem/io/scene.h"
#include "screwfem/model/data.h"

namespace screwfem {

class VtkWriter {
 public:
  // Creates the directory if needed (throws InputError if it cannot) and lays out the frames
  // of `model`: which point each node, joint and body segment becomes, the cells and their
  // ids, and (binary) the whole file but its doubles. Reserves room for `expected_frames`
  // frames, so that writing up to that many allocates nothing.
  void Open(const std::string& dir, const Model& model, VtkFormat format = VtkFormat::kBinary,
            int expected_frames = 0, bool rod_fields = false);
  // Writes the next frame of data's current state at `time` (data of the model given to Open;
  // `load_factor` scales the rods' actuation in the rod fields, as in statics).
  // Returns false on a write error (errno kept; the incomplete frame file is removed and not
  // counted). Allocates no memory (binary, or ascii once its text buffer has grown to a
  // frame's size) while the frames fit the reserved count.
  bool WriteFrame(const Model& model, const Data& data, double time, double load_factor = 1.0);
  // Writes motion.pvd listing the frames written so far. Returns false on a write error.
  bool WriteCollection() const;
  int frames() const { return static_cast<int>(times_.size()); }
  const std::string& dir() const { return dir_; }
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
  };
  void LayOut(const Model& model);
  void CalcPoints(const Model& model, const Data& data);
  void ComposeBinaryImage();
  void ComposeAsciiImage(double time);
  bool WriteImage();

  std::string dir_, path_;  // path_: the frame file being written (capacity kept)
  VtkFormat format_ = VtkFormat::kBinary;
  std::vector<PointSource> sources_;
  // Cells (constant): vertices then lines, as VTK stores them.
  std::vector<long long> vert_connectivity_, vert_offsets_, line_connectivity_, line_offsets_;
  std::vector<int> point_joint_, cell_rod_, cell_body_, cell_joint_;
  // Per-frame values, 3 per point.
  std::vector<double> frame_axes_[3], velocity_, position_;
  // The contact force on the shape at each contact pair's point (zero elsewhere and when the
  // pair is inactive), for glyphs.
  std::vector<double> contact_force_;
  // Per contact segment, filled at each frame from the pairs the broad phase found: the sum of
  // the contact forces on it, and of its contact points weighted by |F| (and the weights).
  std::vector<Vec3> segment_force_, segment_point_;
  std::vector<double> segment_weight_;
  // The file: binary, composed at Open, with the byte offsets of the per-frame values;
  // ascii, recomposed per frame in the same buffer.
  std::string image_;
  std::size_t time_at_ = 0, frame_axes_at_[3] = {0, 0, 0}, velocity_at_ = 0, position_at_ = 0,
              contact_force_at_ = 0;
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
