// The threads of the parallel assembly (docs/architecture.md, "Parallel assembly"): a pool of
// worker threads created once, at set-up, and the fixed-size ring buffer that the threads fill
// with rod element terms, block by block. Data owns one (Data::parallel); nothing here
// allocates after Set.
#pragma once

#include <atomic>
#include <condition_variable>
#include <exception>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include <Eigen/Core>

namespace screwfem {

// A fixed set of threads that run one job at a time. Run(job, context) calls job(context, w)
// for w = 0 .. size() - 1, w = 0 on the calling thread and the others on the pool's threads,
// and returns when every call has returned. A job is a plain function and a pointer, so that
// starting one allocates nothing (no std::function). Between jobs the threads spin briefly,
// then sleep on a condition variable; the destructor wakes and joins them.
class ThreadPool {
 public:
  using Job = void (*)(void* context, int worker);
  explicit ThreadPool(int threads);  // threads >= 1: threads - 1 are started
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;
  int size() const { return size_; }
  // The first exception that a call of the job threw is rethrown here, after all returned.
  void Run(Job job, void* context);

 private:
  void Work(int worker);
  int size_ = 1;
  std::vector<std::thread> threads_;
  std::mutex mutex_;
  std::condition_variable start_, done_;
  Job job_ = nullptr;
  void* context_ = nullptr;
  std::atomic<unsigned long> generation_{0};  // jobs started
  std::atomic<int> pending_{0};               // calls of the current job not yet returned
  bool stop_ = false;                         // under mutex_
  std::exception_ptr error_;                  // under mutex_
};

// The number of processors this process may run on (sched_getaffinity; at least 1).
int AvailableCores();

// One rod element's part of an assembly, computed by a thread of the parallel assembly and
// scattered in element order by the calling thread (assemble/assemble.cpp, AddKindParallel):
// the element's terms reduced to what the scatter adds, the node blocks already combined
// (c_K K T + c_M M + c_C C, as the serial scatter forms them).
struct ParallelItemTerms {
  Eigen::Matrix<double, 12, 12> matrix;  // 6 x 6 node blocks (a, b), those with unknowns set
  Eigen::Matrix<double, 12, 1> residual;
  int item = 0;            // the kind's item (a rod element's index)
  int nodes[2] = {0, 0};   // its nodes
  int dofs[2] = {-1, -1};  // their first unknowns (-1: none)
  double force_scale = 0.0, term_scale = 0.0;
  double failure = 0.0;  // Calc failed: the value out of range
  bool ok = true;        // Calc succeeded
  bool active = true;    // the item contributes (ElementTerms::active)
};

// The parallel assembly's workspace in Data: the pool and a ring buffer of `items` items in
// blocks of 8, each block with a flag that says which block of the assembly it holds
// (docs/architecture.md, "Parallel assembly"). With threads() == 1 there is no pool and no buffer and
// the assembly runs the serial loop. Copying a Data makes a pool of its own with as many
// threads (copies are independent simulations); a copy assigned onto a workspace with the same
// settings keeps its pool and buffers.
class ParallelAssembly {
 public:
  ParallelAssembly() = default;
  ParallelAssembly(const ParallelAssembly& other) { Set(other.threads_, other.chunk_); }
  ParallelAssembly& operator=(const ParallelAssembly& other) {
    if (this != &other) Set(other.threads_, other.chunk_);
    return *this;
  }
  ParallelAssembly(ParallelAssembly&&) noexcept = default;
  ParallelAssembly& operator=(ParallelAssembly&&) noexcept = default;
  ~ParallelAssembly() = default;  // the pool's threads are joined here

  // threads >= 1 (1: serial, the pool and buffers are released), items >= 8 (rounded up to a
  // multiple of 8). Allocates: call at set-up, never inside a step.
  void Set(int threads, int items);
  int threads() const { return threads_; }
  ThreadPool* pool() const { return pool_.get(); }
  // The ring of items: the threads fill them, the calling thread scatters them.
  std::vector<ParallelItemTerms>& items() { return items_; }
  // One flag per block of 8 items of the ring.
  std::atomic<long>* ready() { return ready_.get(); }

 private:
  int threads_ = 1, chunk_ = 0;
  std::unique_ptr<ThreadPool> pool_;
  std::vector<ParallelItemTerms> items_;
  std::unique_ptr<std::atomic<long>[]> ready_;
};

}  // namespace screwfem
