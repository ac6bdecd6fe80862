// A request to end a long computation early (a signal, Python's KeyboardInterrupt). The
// solvers poll it before every Newton iteration of a static load step and before every
// (sub)step attempt of a time step, and return a result marked `interrupted`.
#pragma once

#include <atomic>

namespace screwfem {

struct StopRequest {
  // Set asynchronously (e.g. by a signal handler) to a non-zero value, conventionally the
  // number of the signal that asked to stop; 0 while the computation may go on.
  const std::atomic<int>* flag = nullptr;
  // Polled in the computing thread: returns true to stop (e.g. a pending Python signal).
  bool (*poll)(void* context) = nullptr;
  void* context = nullptr;

  bool Requested() const {
    return (flag != nullptr && flag->load(std::memory_order_relaxed) != 0) ||
           (poll != nullptr && poll(context));
  }
  // The value of `flag` (the signal number by convention), 0 when there is none.
  int Signal() const { return flag != nullptr ? flag->load(std::memory_order_relaxed) : 0; }
};

}  // namespace screwfem
