// Stepping many Simulations at once for screwfem.VectorEnv (python/screwfem/_env.py): the
// physics of n independent copies runs on C++ threads with the GIL released. Each Simulation
// owns its Scene (and so its Model), Data and Integrator, so the threads share nothing; the
// threads call only the C++ API (screwfem::Advance), never Python.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <exception>
#include <functional>
#include <mutex>
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

// The worker threads of _step_many: hardware_concurrency - 1 of them, started at the first
// call that needs one and kept, waiting between calls (polling for kSpin, then on a condition
// variable). Starting a thread per call instead cost the caller about 30 us of CPU time per
// call on the 2-core test machine (two pendulums of a 7 us step each: 47 us of the caller's
// CPU on two threads against 20 us on one; with the pool 16 against 14 us), and the VectorEnv
// benchmark's projected ratio n = 2 / n = 1 was 1.58 against 1.88 with the pool. The pool is
// never destroyed: its threads, detached, end with the process (a static pool's destructor
// would run at exit while they wait). A forked child has none of its parent's threads, so a
// pool belongs to the process that made it and a child makes its own.
class StepPool {
 public:
  explicit StepPool(int workers) : pid_(getpid()), workers_(workers) {
    for (int w = 1; w <= workers; ++w) std::thread([this, w] { Work(w); }).detach();
  }
  int workers() const { return workers_; }
  pid_t pid() const { return pid_; }

  // Runs share(t) for t in [0, threads): share 0 on the calling thread, share t on worker t.
  // Calls from several Python threads (each released the GIL) take turns.
  void Run(int threads, const std::function<void(int)>& share) {
    std::lock_guard<std::mutex> turn(run_mutex_);
    job_.store(&share, std::memory_order_relaxed);
    active_.store(threads, std::memory_order_relaxed);
    pending_.store(threads - 1, std::memory_order_relaxed);
    {
      // Under the mutex, so that a worker about to block sees the new generation or is woken.
      std::lock_guard<std::mutex> lock(mutex_);
      generation_.fetch_add(1, std::memory_order_release);  // publishes the job
    }
    wake_.notify_all();
    share(0);
    if (!SpinUntil([this] { return pending_.load(std::memory_order_acquire) == 0; })) {
      std::unique_lock<std::mutex> lock(mutex_);
      done_.wait(lock, [this] { return pending_.load(std::memory_order_acquire) == 0; });
    }
  }

 private:
  // Polls `ready` for up to kSpin, yielding the processor between polls; true once it holds.
  // A thread that waits this way catches the next call (or the end of the current one)
  // without the sleep and wake-up of the condition variable: on the soft-arm benchmark
  // (bench/python_vector_env.py, n = 2 against n = 1, the run at raised priority) 1.45x
  // against 1.07x without it. Polling with the pause instruction instead of a yield did as
  // well there (1.49x) but, on the machine saturated by other sessions, cost the run its
  // share of the processor (0.68x against 0.96x without polling; with the yield 0.94x).
  template <class Ready>
  static bool SpinUntil(const Ready& ready) {
    const auto end = std::chrono::steady_clock::now() + kSpin;
    for (unsigned i = 0;; ++i) {
      if (ready()) return true;
      if ((i & 15) == 0 && std::chrono::steady_clock::now() >= end) return ready();
      std::this_thread::yield();
    }
  }
  static constexpr std::chrono::microseconds kSpin{200};

  void Work(int index) {
    unsigned long seen = 0;
    for (;;) {
      const auto changed = [&] { return generation_.load(std::memory_order_acquire) != seen; };
      if (!SpinUntil(changed)) {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(lock, changed);
      }
      seen = generation_.load(std::memory_order_acquire);
      if (index >= active_.load(std::memory_order_relaxed)) continue;  // not needed this call
      (*job_.load(std::memory_order_relaxed))(index);
      if (pending_.fetch_sub(1, std::memory_order_acq_rel) == 1) {
        std::lock_guard<std::mutex> lock(mutex_);  // the caller checks pending_ under it
        done_.notify_one();
      }
    }
  }

  const pid_t pid_;
  const int workers_;
  std::mutex run_mutex_;  // one call at a time
  std::mutex mutex_;      // for the waits below
  std::condition_variable wake_, done_;
  std::atomic<const std::function<void(int)>*> job_{nullptr};
  std::atomic<unsigned long> generation_{0};  // one per call
  std::atomic<int> active_{0};                // threads of the current call, the caller included
  std::atomic<int> pending_{0};               // workers of the current call not yet done
};

// The pool of this process (made with the GIL held, so by one thread at a time).
StepPool& Pool(int workers) {
  static StepPool* pool = nullptr;
  if (pool == nullptr || pool->pid() != getpid()) pool = new StepPool(workers);
  return *pool;
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
    sims[i]->CheckInputsFinite("_step_many: sims[" + std::to_string(i) + "]");
  }
  std::vector<Simulation*> sorted(sims);
  std::sort(sorted.begin(), sorted.end());
  if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end())
    throw InputError("_step_many: the same Simulation appears twice in sims");

  const int n = static_cast<int>(sims.size());
  std::vector<std::string> errors(sims.size());
  if (n == 0) return errors;
  const int hardware = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  const int threads = std::max(1, std::min({n, hardware, max_threads > 0 ? max_threads : n}));
  // Thread t steps the contiguous share [n t / threads, n (t + 1) / threads); the calling
  // thread takes share 0, so one copy (or max_threads = 1) involves no other thread.
  const std::function<void(int)> share = [&](int t) {
    const int begin = static_cast<int>(static_cast<long>(n) * t / threads);
    const int end = static_cast<int>(static_cast<long>(n) * (t + 1) / threads);
    for (int i = begin; i < end; ++i)
      errors[static_cast<std::size_t>(i)] =
          StepOne(*sims[static_cast<std::size_t>(i)], h, substeps);
  };
  StepPool* pool = threads > 1 ? &Pool(hardware - 1) : nullptr;
  py::gil_scoped_release release;
  if (pool != nullptr)
    pool->Run(threads, share);
  else
    share(0);
  return errors;
}

}  // namespace

void BindEnv(py::module_& m) {
  m.def("_step_many", &StepMany, py::arg("sims"), py::arg("h"), py::arg("substeps") = 1,
        py::arg("max_threads") = 0,
        R"doc(_step_many(sims, h, substeps=1, max_threads=0) -> list[str]

Advances every Simulation in `sims` (a list of distinct, initialised Simulations) by `substeps`
steps of exactly h [s] each, as `substeps` calls of sim.step(h) would, with the GIL released,
on up to max_threads threads (0: no limit; never more than len(sims) nor the hardware
threads): the calling thread and workers of a pool kept between calls, each stepping a
contiguous share of the list. Calls from several Python threads take turns on the pool (one
Simulation steps on the calling thread alone). Returns one string per simulation: empty on
success, otherwise the message of the failed step (that simulation then stops at the start of
the failed step; the others are unaffected). Ctrl-C is not polled inside the call. Do not use
the simulations from other Python threads during the call. The stepping engine of
screwfem.VectorEnv and screwfem.Env.)doc");
}

}  // namespace screwfem::python
