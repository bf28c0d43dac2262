// -----------------------------------------------------------------------------
// wp_fe_damped_stiff: the FE plate with stiffness-proportional Rayleigh damping C = b K (zeta = 2
// at omega_max): the implicit step needs a linear solve with M + kappa b K, here Newton with a
// matrix-free SPGMR, or with the exact df/dv factored once by KLU. The scene, its reference (modal
// closed form), its curves and its checks: bench/fe_damped_scene.h. Usage: wp_fe_damped_stiff
// [--csv FILE] [--quick] Exit code 0 when the modes converged, every run succeeded and the scene's
// accuracy checks hold; never on a timing.
// -----------------------------------------------------------------------------
#include "fe_damped_scene.h"

int main(int argc, char** argv) {
  return fed::DampedMain(argc, argv, fed::Damping::kStiffness, "fe_damped_stiff");
}
