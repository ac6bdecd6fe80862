// libFuzzer harness: ParseScene (which builds the Model), then the analysis for a few steps:
// a static solve, or the dynamic start and three time steps. Models beyond 20000 unknowns
// stop after the build (a valid scene may be that large; the time per input must stay small).
// Failures as in fuzz_parse.cpp; a failed step or static solve is a valid outcome.
#include <algorithm>
#include <cstdlib>
#include <string>

#include "fuzz_input.h"
#include "screwfem/io/scene.h"
#include "screwfem/model/errors.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const screwfem::fuzz::Input in = screwfem::fuzz::SplitInput(data, size);
  screwfem::Scene scene;
  try {
    scene = screwfem::ParseScene(in.scene, screwfem::fuzz::kSource, in.overrides);
  } catch (const screwfem::InputError& e) {
    if (std::string(e.what()).rfind(screwfem::fuzz::kSource, 0) != 0) std::abort();
    return 0;
  }
  const screwfem::Model& model = scene.model;
  if (model.num_unknowns() > 20000) return 0;
  screwfem::Data d = screwfem::MakeData(model);
  const screwfem::AnalysisSettings& a = scene.analysis;
  if (a.kind == screwfem::AnalysisKind::kStatic) {
    screwfem::StaticOptions so = a.statics;
    so.load_steps = std::min(so.load_steps, 3);
    so.max_halvings = std::min(so.max_halvings, 2);
    // Arc length may take many short steps; a few show the path code works on the input.
    so.max_steps = so.max_steps == 0 ? 10 : std::min(so.max_steps, 10);
    screwfem::SolveStatic(model, d, so);
    return 0;
  }
  d.time = a.start_time;
  screwfem::Integrator integ;
  std::string why;
  if (!screwfem::InitializeDynamics(model, d, integ, a.dynamic, &why)) return 0;
  for (int n = 0; n < 3; ++n)
    if (!screwfem::Step(model, d, integ, a.step).ok) break;
  return 0;
}
