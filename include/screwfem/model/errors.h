// Error types. InputError: the user's model or scene is invalid (the message names what and
// where). SolverError: a numerical failure that the caller chose to turn into an exception.
#pragma once

#include <stdexcept>
#include <string>

namespace screwfem {

class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class SolverError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Always-on internal invariant check (not for user input): aborts with a message.
[[noreturn]] void InternalCheckFailed(const char* condition, const char* file, int line);
#define SCREWFEM_CHECK(cond) \
  ((cond) ? static_cast<void>(0) : ::screwfem::InternalCheckFailed(#cond, __FILE__, __LINE__))

}  // namespace screwfem
