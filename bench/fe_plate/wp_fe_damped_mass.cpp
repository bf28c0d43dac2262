// -----------------------------------------------------------------------------
// wp_fe_damped_mass: the FE plate with mass-proportional Rayleigh damping C = a M (5 % of critical
// in mode 1): with lumped M the implicit step is diagonal, so it must stay an explicit-cost step.
// The scene, its reference (modal closed form), its curves and its checks:
// bench/fe_damped_scene.h.
// Usage: wp_fe_damped_mass [--csv FILE] [--quick]
// Exit code 0 when the modes converged, every run succeeded and the scene's
// accuracy checks hold; never on a timing.
// -----------------------------------------------------------------------------
#include "fe_damped_scene.h"

int main(int argc, char** argv) {
  return fed::DampedMain(argc, argv, fed::Damping::kMass, "fe_damped_mass");
}
