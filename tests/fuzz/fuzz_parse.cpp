// libFuzzer harness: ParseScene with overrides (tests/fuzz/fuzz_input.h). Any exception other
// than InputError, an InputError that does not name the scene, a sanitizer report, a leak, a
// timeout or an out-of-memory is a failure (scripts/run-tests.sh runs it; failing inputs go to
// tests/fuzz/regressions/parse, which ctest replays).
#include <cstdlib>
#include <string>

#include "fuzz_input.h"
#include "screwfem/io/scene.h"
#include "screwfem/model/errors.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const screwfem::fuzz::Input in = screwfem::fuzz::SplitInput(data, size);
  try {
    const screwfem::Scene scene =
        screwfem::ParseScene(in.scene, screwfem::fuzz::kSource, in.overrides);
  } catch (const screwfem::InputError& e) {
    if (std::string(e.what()).rfind(screwfem::fuzz::kSource, 0) != 0) std::abort();
  }
  return 0;
}
