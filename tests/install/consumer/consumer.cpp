// Uses an installed screwfem: builds a compound pendulum with ModelBuilder, released from the
// horizontal, and integrates half a period; the closed form puts it at the opposite horizontal
// then. Loads a scene file (argv[1]) through the io library. Exits non-zero on any mismatch.
#include <cmath>
#include <cstdio>

#include "screwfem/build/model_builder.h"
#include "screwfem/io/scene.h"
#include "screwfem/solve/dynamics.h"

int main(int argc, char** argv) {
  using namespace screwfem;
  constexpr double kL = 0.4, kMass = 0.2, kG = 9.81, kJ = 1e-6;
  ModelBuilder b;
  const NodeId node = b.AddNode(SE3::Identity(), "link");
  b.AddRigidBody("link", node, kMass, Vec3(kL, 0, 0), kJ * Mat3::Identity());
  b.AddJointAt("hinge", JointType::kRevolute, kGround, node, Vec3::Zero(), Vec3::UnitY());
  b.SetGravity(Vec3(0, 0, -kG));
  const Model model = b.Build();
  Data data = MakeData(model);
  Integrator integ;
  if (!InitializeDynamics(model, data, integ, DynamicOptions{})) return 1;
  // Period of a pendulum of amplitude pi/2: 4 sqrt(I_O / (m g L)) K(sin(pi/4)).
  const double period =
      4.0 * std::sqrt((kJ + kMass * kL * kL) / (kMass * kG * kL)) * 1.8540746773013719;
  const double h = 1e-4;
  const int steps = static_cast<int>(std::lround(0.5 * period / h));
  for (int i = 0; i < steps; ++i)
    if (!Step(model, data, integ, 0.5 * period / steps).ok) return 2;
  const double x = data.H[0].Act(Vec3(kL, 0, 0)).x();
  std::printf("consumer: x(T/2) = %.9f m, closed form %.9f m\n", x, -kL);
  if (std::abs(x + kL) > 1e-4) return 3;
  if (argc > 1) {
    const Scene scene = LoadScene(argv[1]);
    std::printf("consumer: scene '%s' with %zu joint(s)\n", argv[1], scene.model.joints.size());
    if (scene.model.joints.size() != 1) return 4;
  }
  std::printf("consumer: ok\n");
  return 0;
}
