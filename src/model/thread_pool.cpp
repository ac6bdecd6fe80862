#include "screwfem/model/thread_pool.h"

#include <sched.h>

#include <algorithm>

namespace screwfem {

namespace {

// Spins of a thread waiting for a job or for its end before it sleeps: the gap between two
// chunks of an assembly (the scatter of one chunk, tens of microseconds) is shorter than a
// sleep and a wake-up.
constexpr int kPoolSpins = 2000;

inline void PoolPause() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#endif
}

}  // namespace

ThreadPool::ThreadPool(int threads) : size_(std::max(1, threads)) {
  threads_.reserve(static_cast<std::size_t>(size_ - 1));
  for (int w = 1; w < size_; ++w) threads_.emplace_back([this, w] { Work(w); });
}

ThreadPool::~ThreadPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  start_.notify_all();
  for (std::thread& t : threads_) t.join();
}

void ThreadPool::Run(Job job, void* context) {
  if (size_ == 1) {
    job(context, 0);
    return;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    job_ = job;
    context_ = context;
    error_ = nullptr;
    pending_.store(size_ - 1, std::memory_order_relaxed);
    generation_.fetch_add(1, std::memory_order_release);
  }
  start_.notify_all();
  std::exception_ptr error;
  try {
    job(context, 0);
  } catch (...) {
    error = std::current_exception();
  }
  for (int i = 0; i < kPoolSpins && pending_.load(std::memory_order_acquire) > 0; ++i) PoolPause();
  if (pending_.load(std::memory_order_acquire) > 0) {
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [&] { return pending_.load(std::memory_order_acquire) == 0; });
  }
  std::lock_guard<std::mutex> lock(mutex_);
  if (!error) error = error_;
  if (error) std::rethrow_exception(error);
}

void ThreadPool::Work(int worker) {
  unsigned long seen = 0;
  for (;;) {
    for (int i = 0; i < kPoolSpins && generation_.load(std::memory_order_acquire) == seen; ++i)
      PoolPause();
    Job job;
    void* context;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      start_.wait(lock,
                  [&] { return stop_ || generation_.load(std::memory_order_acquire) != seen; });
      if (stop_) return;
      seen = generation_.load(std::memory_order_acquire);
      job = job_;
      context = context_;
    }
    try {
      job(context, worker);
    } catch (...) {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!error_) error_ = std::current_exception();
    }
    if (pending_.fetch_sub(1, std::memory_order_acq_rel) == 1) {
      // The lock orders this notification after the caller's check of pending_.
      { std::lock_guard<std::mutex> lock(mutex_); }
      done_.notify_one();
    }
  }
}

int AvailableCores() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof(set), &set) == 0) return std::max(1, CPU_COUNT(&set));
  return std::max(1u, std::thread::hardware_concurrency());
}

void ParallelAssembly::Set(int threads, int items) {
  threads = std::max(1, threads);
  items = threads > 1 ? (std::max(8, items) + 7) / 8 * 8 : 0;
  if (threads == threads_ && items == chunk_ && (threads == 1 || pool_)) return;
  pool_.reset();
  items_.clear();
  items_.shrink_to_fit();
  ready_.reset();
  threads_ = threads;
  chunk_ = items;
  if (threads == 1) return;
  items_.resize(static_cast<std::size_t>(items));
  ready_ = std::make_unique<std::atomic<long>[]>(static_cast<std::size_t>(items / 8));
  pool_ = std::make_unique<ThreadPool>(threads);
}

}  // namespace screwfem
