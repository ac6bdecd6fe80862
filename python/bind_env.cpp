// Stepping many Simulations at once for screwfem.VectorEnv (python/screwfem/_env.py): the
// physics of n independent copies runs on C++ threads with the GIL released. Each Simulation
// owns its Scene (and so its Model), Data and Integrator, so the threads share nothing; the
// threads call only the C++ API (screwfem::Advance), never Python.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <string>
#include <thread>
#include <vector>

#include "bind.h"
#include "screwfem/model/errors.h"
#include "screwfem/solve/advance.h"
#include "simulation.h"

namespace py = pybind11;

namespace screwfem::python {

namespace {

// `substeps` steps of exactly h, as `substeps` calls of Simulation.step(h) make them (the same
// Advance call, without the signal polling): "" on success, otherwise the message of the step
// that failed, the state left at that step's start (Simulation.step's SolverError message).
std::string StepOne(Simulation& sim, double h, int substeps) noexcept {
  try {
    for (int k = 0; k < substeps; ++k) {
      const StepResult r = screwfem::Advance(sim.model(), sim.data(), sim.integrator(),
                                             StepPolicy::Fixed(h), sim.data().time + h);
      if (!r.ok) return r.message.empty() ? std::string("time step failed") : r.message;
    }
    return {};
  } catch (const std::exception& e) {
    // Nothing may leave a thread: an exception here would call std::terminate.
    return std::string("time step failed: ") + e.what();
  } catch (...) {
    return "time step failed: unknown C++ exception";
  }
}

std::vector<std::string> StepMany(const std::vector<Simulation*>& sims, double h, int substeps,
                                  int max_threads) {
  if (!(std::isfinite(h) && h > 0.0)) throw InputError("_step_many: h must be a time > 0 s");
  if (substeps < 1) throw InputError("_step_many: substeps must be >= 1");
  // Checked with the GIL held, before any thread starts: a Simulation that is not initialised,
  // or one listed twice (two threads would step the same Data).
  for (std::size_t i = 0; i < sims.size(); ++i) {
    if (sims[i] == nullptr) throw InputError("_step_many: sims[" + std::to_string(i) + "] is None");
    if (!sims[i]->initialized())
      throw std::logic_error("_step_many: sims[" + std::to_string(i) +
                             "] is not initialized (call initialize() first)");
  }
  std::vector<Simulation*> sorted(sims);
  std::sort(sorted.begin(), sorted.end());
  if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end())
    throw InputError("_step_many: the same Simulation appears twice in sims");

  const int n = static_cast<int>(sims.size());
  std::vector<std::string> errors(sims.size());
  if (n == 0) return errors;
  const int hardware = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  int threads = std::min(n, max_threads > 0 ? max_threads : hardware);
  threads = std::max(threads, 1);
  {
    py::gil_scoped_release release;
    // Thread t steps the contiguous share [n t / threads, n (t + 1) / threads); the calling
    // thread takes share 0, so one copy (or max_threads = 1) starts no thread at all. Threads
    // are started per call: about 20 us each, against the milliseconds an env step of a soft
    // robot takes, and no pool outlives the call (nothing to shut down at exit or after fork).
    const auto share = [&](int t) {
      const int begin = static_cast<int>(static_cast<long>(n) * t / threads);
      const int end = static_cast<int>(static_cast<long>(n) * (t + 1) / threads);
      for (int i = begin; i < end; ++i)
        errors[static_cast<std::size_t>(i)] =
            StepOne(*sims[static_cast<std::size_t>(i)], h, substeps);
    };
    std::vector<std::thread> pool;
    pool.reserve(static_cast<std::size_t>(threads - 1));
    for (int t = 1; t < threads; ++t) pool.emplace_back(share, t);
    share(0);
    for (std::thread& th : pool) th.join();
  }
  return errors;
}

}  // namespace

void BindEnv(py::module_& m) {
  m.def("_step_many", &StepMany, py::arg("sims"), py::arg("h"), py::arg("substeps") = 1,
        py::arg("max_threads") = 0,
        R"doc(_step_many(sims, h, substeps=1, max_threads=0) -> list[str]

Advances every Simulation in `sims` (a list of distinct, initialised Simulations) by `substeps`
steps of exactly h [s] each, as `substeps` calls of sim.step(h) would, on up to max_threads
threads (0: one per hardware thread, never more than len(sims)), each stepping a contiguous
share of the list, with the GIL released. Returns one string per simulation: empty on
success, otherwise the message of the failed step (that simulation then stops at the start of
the failed step; the others are unaffected). Ctrl-C is not polled inside the call. Do not use
the simulations from other Python threads during the call. The stepping engine of
screwfem.VectorEnv and screwfem.Env.)doc");
}

}  // namespace screwfem::python
