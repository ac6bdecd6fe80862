#include "screwfem/model/errors.h"

#include <cstdio>
#include <cstdlib>

namespace screwfem {

void InternalCheckFailed(const char* condition, const char* file, int line) {
  std::fprintf(stderr, "screwfem: internal check failed: %s (%s:%d)\n", condition, file, line);
  std::abort();
}

std::string FormatNumbers(const char* format, double a, double b, double c) {
  char buf[256];
  std::snprintf(buf, sizeof buf, format, a, b, c);
  return buf;
}

}  // namespace screwfem
