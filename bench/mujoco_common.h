// What the benchmarks against MuJoCo share (mujoco_bench.cpp: the spring chain;
// mujoco_box_bench.cpp: the sliding box): trajectories sampled at fixed times and their
// distance, a model loaded from MJCF text, and screwfem's stepping loop that samples a run the
// way `screwfem run` writes its rows.
#pragma once

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "screwfem/model/model.h"
#include "screwfem/solve/dynamics.h"

namespace screwfem::mujoco_common {

// Points at the sample times k * sample, k = 1..n: 3 values per point, points in order.
using Trajectory = std::vector<double>;

// The largest distance between corresponding points of two trajectories.
inline double MaxDistance(const Trajectory& a, const Trajectory& b) {
  double d = 0.0;
  for (std::size_t i = 0; i + 2 < a.size() && i + 2 < b.size(); i += 3)
    d = std::max(d, std::hypot(a[i] - b[i], a[i + 1] - b[i + 1], a[i + 2] - b[i + 2]));
  return d;
}

inline double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

struct MjModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
struct MjDataDeleter {
  void operator()(mjData* d) const { mj_deleteData(d); }
};

// The model of MJCF text `xml`, through MuJoCo's virtual file system under `name`.
inline std::unique_ptr<mjModel, MjModelDeleter> LoadMjcf(const std::string& xml, const char* name) {
  auto vfs = std::make_unique<mjVFS>();  // large: on the heap
  mj_defaultVFS(vfs.get());
  const int size = static_cast<int>(xml.size());
  if (mj_makeEmptyFileVFS(vfs.get(), name, size) != 0)
    throw std::runtime_error("mj_makeEmptyFileVFS failed");
  const int f = mj_findFileVFS(vfs.get(), name);
  std::memcpy(vfs->filedata[f], xml.data(), static_cast<std::size_t>(size));
  char error[1000] = "";
  mjModel* m = mj_loadXML(name, vfs.get(), error, sizeof(error));
  mj_deleteVFS(vfs.get());
  if (!m) throw std::runtime_error(std::string("MuJoCo: ") + error);
  return std::unique_ptr<mjModel, MjModelDeleter>(m);
}

// screwfem's stepping loop to `horizon`, sampled every `sample` (record(state, k) for the k-th
// sample, k = 0..n-1 at (k + 1) sample): fixed steps of h (a divisor of `sample`), or
// error-controlled steps (`adaptive`) with the samples inside a step interpolated into `out`
// (dense output, as `screwfem run` writes rows). False if a step failed.
template <class Record>
bool RunSampled(const Model& model, Data& data, Data& out, Integrator& integ, bool adaptive,
                double h, double sample, double horizon, Record&& record) {
  const int samples = static_cast<int>(std::lround(horizon / sample));
  bool ok = true;
  if (!adaptive) {
    const int per_sample = static_cast<int>(std::lround(sample / h));
    for (int k = 0; k < samples && ok; ++k) {
      for (int j = 0; j < per_sample && ok; ++j) ok = Step(model, data, integ, h).ok;
      record(data, k);
    }
  } else {
    int k = 0;
    while (ok && k < samples) {
      ok = AdaptiveStep(model, data, integ, horizon).ok;
      while (ok && k < samples && (k + 1) * sample <= data.time + 1e-12) {
        InterpolateStep(model, data, integ, (k + 1) * sample, out);
        record(out, k);
        ++k;
      }
    }
  }
  return ok;
}

}  // namespace screwfem::mujoco_common
