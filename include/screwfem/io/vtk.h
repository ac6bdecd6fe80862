// ParaView output of a run: one ASCII PolyData file per recorded frame and a Collection file
// that lists them with their times.
//
// DIR/frame_NNNNN.vtp   the mechanism at one time (world frame, metres):
//   vertices   one per joint, at the joint frame's origin (side A);
//   polylines  one per rod, through its nodes in order;
//   lines      per rigid body, from its node origin to its centre of mass and to every joint
//              attachment point on it (so a link between two joints is drawn between them).
//   Point data: frame_x, frame_y, frame_z (axes of the node frame, the section frame on rods,
//               the joint frame at joints), velocity [m/s], joint_id (-1 except at joints).
//   Cell data:  rod_id, body_id, joint_id (-1 where they do not apply).
//   Field data: TimeValue [s].
// DIR/motion.pvd         the Collection, written once (atomically) when the run ends, also
//                        when it is interrupted or fails: it lists exactly the complete frame
//                        files on disk. (Rewriting it after every frame made a run quadratic
//                        in its number of frames.)
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "screwfem/model/data.h"

namespace screwfem {

class VtkWriter {
 public:
  // Creates the directory if needed. Throws InputError if it cannot.
  void Open(const std::string& dir);
  // Writes the next frame of data's current state at `time`. Returns false on a write error
  // (errno kept; the incomplete frame file is removed and not counted).
  bool WriteFrame(const Model& model, const Data& data, double time);
  // Writes motion.pvd listing the frames written so far. Returns false on a write error.
  bool WriteCollection() const;
  int frames() const { return static_cast<int>(frames_.size()); }
  const std::string& dir() const { return dir_; }

 private:
  std::string dir_;
  std::vector<std::pair<double, std::string>> frames_;  // time, file name
};

}  // namespace screwfem
