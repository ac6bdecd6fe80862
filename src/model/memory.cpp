#include "screwfem/model/memory.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "screwfem/model/data.h"
#include "screwfem/model/errors.h"
#include "screwfem/model/model.h"

namespace screwfem {

namespace {

std::atomic<std::size_t> g_default_limit{0};

// When sysconf cannot tell.
constexpr std::size_t kUnknownPhysicalLimit = std::size_t{16} << 30;

// The sparse LU's storage per pattern (SparseLU, KLU): 12 bytes an entry of the matrix and of
// L + U (a value and a row index), per unknown the column starts and KLU's symbolic analysis
// (its permutations and counts), and per unknown and kept pivot sequence KLU's numeric
// object's arrays (pivots, column pointers and lengths, the diagonal, the scaling). The base
// pattern keeps two sequences (the iteration matrix; the mass matrix of the consistent
// accelerations at the start and restarts) unless its matrices change kind often (up to 8:
// docs/numerics.md, "Sparse direct solve"); a pattern of contact couplings one (the
// iteration matrix). Fitted to the heap of the spheres of bench/pairs_bench.cpp (apart: the
// base pattern; in rows: the base and one of couplings).
constexpr double kSparseEntryBytes = 12.0;
constexpr double kSparseSymbolicBytes = 24.0;
constexpr double kSparseColumnBytes = 20.0;
constexpr double kBasePivotSequences = 2.0;

double SparsePatternBytes(double entries, double factor_nonzeros, double n, double sequences) {
  return entries * kSparseEntryBytes + n * kSparseSymbolicBytes +
         sequences * (factor_nonzeros * kSparseEntryBytes + n * kSparseColumnBytes);
}

}  // namespace

std::size_t PhysicalMemoryBytes() {
  const long pages = sysconf(_SC_PHYS_PAGES);
  const long page = sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || page <= 0) return 0;
  return static_cast<std::size_t>(pages) * static_cast<std::size_t>(page);
}

void SetDefaultMemoryLimit(std::size_t bytes) { g_default_limit.store(bytes); }
std::size_t DefaultMemoryLimit() { return g_default_limit.load(); }

std::size_t ResolveMemoryLimit(std::size_t model_limit) {
  if (model_limit > 0) return model_limit;
  const std::size_t process = g_default_limit.load();
  if (process > 0) return process;
  const std::size_t physical = PhysicalMemoryBytes();
  if (physical == 0) return kUnknownPhysicalLimit;
  return static_cast<std::size_t>(kDefaultMemoryShare * static_cast<double>(physical));
}

std::string DescribeMemoryLimit(std::size_t model_limit) {
  if (model_limit > 0) return "set by ModelBuilder.set_memory_limit";
  if (g_default_limit.load() > 0) return "set by --max-memory or max_memory";
  const std::size_t physical = PhysicalMemoryBytes();
  if (physical == 0) return "the default when the physical memory is unknown";
  char text[96];
  std::snprintf(text, sizeof text, "the default: %.0f %% of the physical memory, %s",
                100.0 * kDefaultMemoryShare, FormatBytes(static_cast<double>(physical)).c_str());
  return text;
}

std::string FormatBytes(double bytes) {
  static const char* const kUnits[] = {"B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  int unit = 0;
  while (bytes >= 1024.0 && unit < 6) {
    bytes /= 1024.0;
    ++unit;
  }
  char text[32];
  if (unit == 0)
    std::snprintf(text, sizeof text, "%.0f B", bytes);
  else
    std::snprintf(text, sizeof text, "%.3g %s", bytes, kUnits[unit]);
  return text;
}

std::size_t ParseMemorySize(const std::string& text, const std::string& setting) {
  const auto fail = [&]() -> std::size_t {
    throw InputError(setting + ": expected a size such as 8G or 512M (K, M, G, T: powers of " +
                     "1024), got '" + text.substr(0, 64) + "'");
  };
  if (text.empty() || text.size() > 64 || std::isspace(static_cast<unsigned char>(text[0])))
    return fail();
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || errno == ERANGE || !std::isfinite(value) || !(value > 0.0))
    return fail();
  std::string unit(end);
  for (char& c : unit) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  double scale = 1.0;
  if (!unit.empty()) {
    const std::string head = unit.substr(0, 1);
    const std::string tail = unit.substr(1);
    if (tail != "" && tail != "B" && tail != "IB") return fail();
    if (head == "B" && tail.empty())
      scale = 1.0;
    else if (head == "K")
      scale = 1024.0;
    else if (head == "M")
      scale = 1024.0 * 1024.0;
    else if (head == "G")
      scale = 1024.0 * 1024.0 * 1024.0;
    else if (head == "T")
      scale = 1024.0 * 1024.0 * 1024.0 * 1024.0;
    else
      return fail();
  }
  const double bytes = std::floor(value * scale);
  if (!(bytes >= 1.0) || bytes >= 1.8e19) return fail();
  return static_cast<std::size_t>(bytes);
}

std::vector<MemoryPart> EstimateDataMemory(const Model& m) {
  std::vector<MemoryPart> parts;
  const double n = std::max(m.num_unknowns(), 1);
  const double kl = m.bandwidth;
  char why[256];
  if (m.sparse_solver) {
    // SparseLU: the matrix in compressed columns (12 bytes an entry, the blocks of the
    // pattern), KLU's symbolic analysis and its factors for the pivot sequences a run keeps
    // (SparsePatternBytes).
    double entries = 0.0;
    for (const SparseLU::Block& b : m.sparse_pattern)
      entries += static_cast<double>(b.rows) * static_cast<double>(b.cols);
    std::snprintf(why, sizeof why,
                  "%d unknowns (nv = %d, nc = %d): %.0f matrix entries and %.0f x %.0f "
                  "entries of L + U (KLU's estimate) x 12 bytes",
                  m.num_unknowns(), m.nv, m.nc, entries, kBasePivotSequences,
                  m.sparse_factor_nonzeros);
    parts.push_back({"sparse LU factors of the iteration matrix",
                     SparsePatternBytes(entries, m.sparse_factor_nonzeros, n, kBasePivotSequences),
                     why});
  } else {
    // BandedLU::Resize: ldab = 2 kl + ku + 1 doubles per column; per unknown 9 ints/doubles
    // more.
    std::snprintf(why, sizeof why,
                  "%d unknowns (nv = %d, nc = %d) x %d band entries (bandwidth %d: 3 x %d + 1) "
                  "x 8 bytes",
                  m.num_unknowns(), m.nv, m.nc, 3 * m.bandwidth + 1, m.bandwidth, m.bandwidth);
    parts.push_back(
        {"banded LU factors of the iteration matrix", n * (3.0 * kl + 1.0) * 8.0 + n * 52.0, why});
  }
  // The state and the Newton workspaces: vectors of n, node frames and tangents, element
  // branch references.
  const double nodes = static_cast<double>(m.nodes.size());
  parts.push_back({"state and Newton workspaces",
                   n * 8.0 * 6.0 + nodes * (sizeof(SE3) + sizeof(Mat6)) +
                       static_cast<double>(m.elements.size()) * sizeof(Vec3) +
                       static_cast<double>(m.joints.size()) * sizeof(SE3),
                   "vectors of the unknowns, node frames and tangents"});
  const double segments = static_cast<double>(m.contact_segments.size());
  if (segments > 0 && MayHaveShapePairs(m) && m.sparse_solver) {
    // The sparse LU's patterns of contact couplings (SelectSparsePattern): the list of
    // couplings (6 per pair of the first pool) and one pattern besides the base (which is
    // kept): the base's blocks and a 6 x 6 coupling per contact segment (72 entries: a pair
    // per neighbour of a chain of spheres or elements) in the matrix and in L + U. A run
    // whose pairs change pattern often keeps up to SparseLU::kCachedPatterns such patterns
    // (bench/RESULTS.md, "Contact pairs in the sparse pattern": the heap of spheres apart and
    // in rows against this estimate).
    double entries = 0.0;
    for (const SparseLU::Block& b : m.sparse_pattern)
      entries += static_cast<double>(b.rows) * static_cast<double>(b.cols);
    const double pool = 4.0 * segments + 64.0;
    std::snprintf(why, sizeof why,
                  "%.0f contact segments: the base pattern with a 6 x 6 coupling per segment "
                  "(72 entries in the matrix and in L + U, one pivot sequence) and the list of "
                  "%.0f couplings",
                  segments, 6.0 * pool);
    parts.push_back(
        {"sparse patterns of pairs of moving shapes",
         pool * 6.0 * 8.0 + SparsePatternBytes(entries + 72.0 * segments,
                                               m.sparse_factor_nonzeros + 72.0 * segments, n, 1.0),
         why});
  } else if (segments > 0 && MayHaveShapePairs(m)) {
    // BandCoupling at its largest (kMaxCoupledNodes): 3 k^2 + 2 k + n doubles, k = 6 nodes.
    const double k = 6.0 * kMaxCoupledNodes;
    std::snprintf(why, sizeof why, "at most %d nodes of 6 unknowns: 3 x %.0f^2 doubles",
                  kMaxCoupledNodes, k);
    parts.push_back(
        {"off-band coupling of pairs of moving shapes",
         (3.0 * k * k + 2.0 * k + n) * 8.0 + (3.0 * kMaxCoupledNodes * kMaxCoupledNodes + n) * 4.0,
         why});
  }
  if (segments > 0 && MayHaveShapePairs(m)) {
    // MakeData: the grid's arrays and the first pool of 4 pairs per segment.
    double buckets = 1;
    while (buckets < 16 * segments) buckets *= 2;
    std::snprintf(why, sizeof why, "%.0f contact segments: the grid and a pool of %.0f pairs",
                  segments, 4 * segments + 64);
    parts.push_back({"broad phase of pairs of moving shapes",
                     segments * (4 * sizeof(Vec3) + 1 + 4 + 8 * (4 + sizeof(Eigen::Vector3i))) +
                         (buckets + 1) * 4 + (4 * segments + 64) * sizeof(ShapePair),
                     why});
  }
  // The stick law's history (Data::contact_anchors, shape_pair_anchors).
  if (KeepsContactAnchors(m)) {
    double bytes = static_cast<double>(m.contact_pairs.size()) * sizeof(ContactAnchor);
    if (segments > 0 && MayHaveShapePairs(m))
      bytes += 2.0 * (4 * segments + 64) * sizeof(ShapePairAnchor);
    parts.push_back({"stick friction's anchors", bytes,
                     "the history of each pair of a shape and an obstacle, and two per pair of "
                     "moving shapes in the pool"});
  }
  // The swept check against tunnelling (Data::crossing_points and its sweep's buffers).
  if (segments > 0 || !m.contact_pairs.empty())
    parts.push_back({"swept check against tunnelling",
                     2.0 * (segments + static_cast<double>(m.contact_pairs.size())) * sizeof(Vec3) +
                         segments * (2 * sizeof(Vec3) + sizeof(int)),
                     "two axis end points per contact segment and obstacle pair, and a sweep's "
                     "box ends and order per segment"});
  return parts;
}

namespace {

template <class T>
double VectorBytes(const std::vector<T>& v) {
  return static_cast<double>(v.capacity() * sizeof(T));
}

}  // namespace

MemoryPart EstimateModelMemory(const Model& m) {
  double bytes =
      sizeof(Model) + VectorBytes(m.nodes) + VectorBytes(m.rods) + VectorBytes(m.elements) +
      VectorBytes(m.bodies) + VectorBytes(m.joints) + VectorBytes(m.point_loads) +
      VectorBytes(m.rod_loads) + VectorBytes(m.tendons) + VectorBytes(m.tendon_segments) +
      VectorBytes(m.force_elements) + VectorBytes(m.actuators) + VectorBytes(m.element_actuators) +
      VectorBytes(m.contact_shapes) + VectorBytes(m.contact_rods) + VectorBytes(m.obstacles) +
      VectorBytes(m.contact_pairs) + VectorBytes(m.contact_segments) +
      static_cast<double>(m.contact_entity_pairs.bytes()) +
      VectorBytes(m.contact_entity_self_skip) + VectorBytes(m.contact_materials) +
      VectorBytes(m.contact_laws) + VectorBytes(m.contact_law_table) + VectorBytes(m.permutation) +
      VectorBytes(m.pattern_last) + VectorBytes(m.redundant_rows);
  for (const Rod& rod : m.rods) bytes += VectorBytes(rod.nodes);
  char why[160];
  std::snprintf(why, sizeof why,
                "%zu nodes of %zu bytes, %zu rod elements of %zu bytes, %zu joints", m.nodes.size(),
                sizeof(Node), m.elements.size(), sizeof(RodElement), m.joints.size());
  return {"model (nodes, elements, joints, ordering)", bytes, why};
}

MemoryPart EstimateIntegratorMemory(const Model& m, const IntegratorMemoryOptions& o) {
  const double nv = m.nv, nc = m.nc, n = m.num_unknowns();
  if (o.statics)
    return {"static solver's workspace", (4.0 * n + nv) * 8.0,
            "4 vectors of the unknowns and 1 of the velocities"};
  // A copy of the configuration (State: node and joint frames, joint coordinates).
  const double state =
      static_cast<double>(m.nodes.size() + m.joints.size()) * sizeof(SE3) + (nv - m.nv_nodes) * 8.0;
  double vectors_nv = 7.0, vectors_nc = 6.0, states = 1.0;
  if (o.adaptive) vectors_nv += 9.0, vectors_nc += 2.0, states += 1.0;
  if (o.perturbed_start) vectors_nv += 2.0, vectors_nc += 1.0, states += 1.0;
  double bytes = (vectors_nv * nv + vectors_nc * nc) * 8.0 + states * state;
  if (o.ggl) bytes += (2.0 * nc * nv + nc * nc * 2.0 + 6.0 * nc + nv) * 8.0;
  char why[160];
  std::snprintf(why, sizeof why, "%.0f vectors of nv = %d, %.0f of nc = %d, %.0f configurations%s",
                vectors_nv, m.nv, vectors_nc, m.nc, states,
                o.ggl ? ", the index-2 constraint matrices" : "");
  return {o.adaptive ? "time integrator's workspace (error-controlled steps)"
                     : "time integrator's workspace",
          bytes, why};
}

std::vector<MemoryPart> EstimateRunMemory(const Model& m, const IntegratorMemoryOptions& o) {
  std::vector<MemoryPart> parts;
  parts.push_back(EstimateModelMemory(m));
  for (MemoryPart& p : EstimateDataMemory(m)) parts.push_back(std::move(p));
  parts.push_back(EstimateIntegratorMemory(m, o));
  return parts;
}

double TotalBytes(const std::vector<MemoryPart>& parts) {
  double total = 0.0;
  for (const MemoryPart& p : parts) total += p.bytes;
  return total;
}

void CheckMemory(const std::vector<MemoryPart>& parts, std::size_t model_limit,
                 const std::string& what, const std::string& hint) {
  const double total = TotalBytes(parts);
  const std::size_t limit = ResolveMemoryLimit(model_limit);
  if (total <= static_cast<double>(limit) || parts.empty()) return;
  const MemoryPart* largest = &parts.front();
  for (const MemoryPart& p : parts)
    if (p.bytes > largest->bytes) largest = &p;
  std::string message =
      what + " needs about " + FormatBytes(total) + ", more than the memory limit of " +
      FormatBytes(static_cast<double>(limit)) + " (" + DescribeMemoryLimit(model_limit) +
      "; --max-memory SIZE or max_memory= change it): the largest part is the " + largest->part +
      ", " + FormatBytes(largest->bytes) + " (" + largest->why + ")";
  if (!hint.empty()) message += ". " + hint;
  throw InputError(message);
}

}  // namespace screwfem
