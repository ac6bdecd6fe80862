// The memory a model needs, estimated before it is allocated, against a limit (docs/limits.md,
// "Memory"). ModelBuilder::Build() checks the parts it is about to allocate (the pairs of moving
// shapes and obstacles, the contact couplings of the solver ordering) and, once the unknowns are ordered, the workspace MakeData will allocate
// (the banded LU factors, the off-band coupling, the broad phase's pair pool); a scene over the
// limit is an InputError naming the part, its bytes, why it is that large and the settings
// that change it. `screwfem check` therefore refuses it without allocating it.
//
// The limit: Model::memory_limit when set (ModelBuilder::SetMemoryLimit), otherwise the
// process default (SetDefaultMemoryLimit: the CLI's --max-memory, Python's max_memory), otherwise
// kDefaultMemoryShare of the physical memory (sysconf).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace screwfem {

struct Model;

// Half of the physical memory by default: a run then leaves room for the system and a second
// run, and fails with a message instead of being killed by the out-of-memory killer.
inline constexpr double kDefaultMemoryShare = 0.5;

// The physical memory of the machine [bytes] (sysconf _SC_PHYS_PAGES x _SC_PAGE_SIZE; 0 when
// unknown).
std::size_t PhysicalMemoryBytes();
// The process default (0: none set, kDefaultMemoryShare of the physical memory applies).
void SetDefaultMemoryLimit(std::size_t bytes);
std::size_t DefaultMemoryLimit();  // the value set (0: none)
// The limit for `model_limit` (a Model::memory_limit; 0: the process default, else the share of
// physical memory; 16 GiB when the physical memory is unknown).
std::size_t ResolveMemoryLimit(std::size_t model_limit = 0);
// Where the limit came from, for messages ("--max-memory / max_memory", "50 % of ...").
std::string DescribeMemoryLimit(std::size_t model_limit = 0);

// "1.5 GiB", "512 MiB", "12 KiB", "100 B" (binary units, 3 significant digits).
std::string FormatBytes(double bytes);
// A size: a number with an optional binary unit, K, M, G, T (or KiB, MiB, GiB, TiB, KB, MB,
// GB, TB: all powers of 1024; case-insensitive), e.g. "8G", "512MiB", "1.5g", "1000000". Throws
// InputError "SETTING: expected a size such as 8G or 512M (K, M, G, T: powers of 1024), got
// '...'" (also for 0 and for sizes that do not fit in 64 bits).
std::size_t ParseMemorySize(const std::string& text, const std::string& setting);

// One allocation of the estimate.
struct MemoryPart {
  std::string part;  // what, e.g. "banded LU factors of the iteration matrix"
  double bytes = 0;  // [bytes] (double: products of sizes cannot overflow)
  std::string why;   // the sizes that make it, e.g. "n = 60000 unknowns x (3 x 59999 + 1) ..."
};

// The parts MakeData allocates for `model` (after Build: its unknowns, bandwidth and contact
// segments): the banded LU, the off-band coupling at its largest, the broad phase's grid and
// pair pool, the state vectors. Bytes of Data, not of the Model.
std::vector<MemoryPart> EstimateDataMemory(const Model& model);
double TotalBytes(const std::vector<MemoryPart>& parts);

// The Model itself: its arrays as allocated (capacities), nodes, rod elements, joints, the
// solver ordering and the contact tables.
MemoryPart EstimateModelMemory(const Model& model);
// The time integrator's workspace (Integrator, solve/dynamics.h) as InitializeDynamics sizes it:
// 7 vectors of nv, 6 of nc and a copy of the configuration; with `adaptive` (step: auto) the
// error control and dense output (PrepareAdaptiveSteps: 9 of nv, 2 of nc, a configuration),
// with `perturbed_start` its saved state, with `ggl` the stabilised index-2 workspace (two
// dense nc x nv matrices). Static analyses: the static solver's 4 vectors of the unknowns and
// one of nv (`statics`).
struct IntegratorMemoryOptions {
  bool statics = false;
  bool adaptive = false;
  bool perturbed_start = false;
  bool ggl = false;
};
MemoryPart EstimateIntegratorMemory(const Model& model, const IntegratorMemoryOptions& options);
// A run's memory: the model, MakeData's parts (EstimateDataMemory) and the integrator's, as
// `screwfem check` prints them. For a dynamic rod (a cantilever of 10^4 elements) it is within
// a few percent of the heap the run allocates (tests/build/memory_test.cpp measures it).
std::vector<MemoryPart> EstimateRunMemory(const Model& model,
                                          const IntegratorMemoryOptions& options);

// Throws InputError when the parts together exceed the model's limit (ResolveMemoryLimit):
// "WHAT needs about 86 GiB, more than the memory limit of 3.9 GiB (50 % of the physical
// memory; --max-memory or max_memory raise it): the largest part is the banded LU factors of
// the iteration matrix, 86 GiB (WHY). HINT". `hint` says how to make the part smaller.
void CheckMemory(const std::vector<MemoryPart>& parts, std::size_t model_limit,
                 const std::string& what, const std::string& hint = {});

}  // namespace screwfem
