// -----------------------------------------------------------------------------
// fe_damped_step_cost: one configuration of the Rayleigh-damped plate
// (bench/fe_damped_scene.h) for a given number of fixed steps, for per-step
// instruction counts under callgrind (Ir(2S) - Ir(S)) / S, so that creation and the
// start are not counted. Not a test and not a main-job scene.
//   fe_damped_step_cost CONFIG STEPS [NY]
// CONFIG: hand-mass, hand-stiff, undamped (CEODE G3_CD explicit, C = 0), mass-pc,
// mass-auto, mass-newton (SPGMR), stiff-newton, stiff-newton-loose (rtol 1e-7),
// stiff-lagged. The mesh is 4 NY x NY elements (default NY = 35: 10 080 DOF); h is
// 0.9 of G3_CD's undamped stable step (0.1 for hand-stiff and stiff-lagged).
// -----------------------------------------------------------------------------
#include <cstdlib>
#include <cstring>

#include "fe_damped_scene.h"

namespace {

struct Cfg {
  const char* name;
  fed::Damping kind;
  bool damped, hand;
  double frac;
  fes::CeodeCfg ce;
};

std::vector<Cfg> Configs() {
  fes::CeodeCfg ex, pc, au, nw, loose;
  pc.vel = au.vel = nw.vel = loose.vel = true;
  pc.mode = CE_IMPLICIT_PC;
  au.mode = CE_IMPLICIT_AUTO;
  au.spgmr = nw.spgmr = loose.spgmr = true;
  loose.nls_rtol = 1e-7;
  using D = fed::Damping;
  return {{"hand-mass", D::kMass, true, true, 0.9, ex},
          {"hand-stiff", D::kStiffness, true, true, 0.1, ex},
          {"undamped", D::kMass, false, false, 0.9, ex},
          {"mass-pc", D::kMass, true, false, 0.9, pc},
          {"mass-auto", D::kMass, true, false, 0.9, au},
          {"mass-newton", D::kMass, true, false, 0.9, nw},
          {"stiff-newton", D::kStiffness, true, false, 0.9, nw},
          {"stiff-newton-loose", D::kStiffness, true, false, 0.9, loose},
          {"stiff-lagged", D::kStiffness, true, false, 0.1, ex}};
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s CONFIG STEPS [NY]\n", argv[0]);
    return 2;
  }
  const long steps = std::atol(argv[2]);
  const int ny = argc > 3 ? std::atoi(argv[3]) : 35;
  for (const Cfg& c : Configs()) {
    if (std::strcmp(c.name, argv[1]) != 0) continue;
    SUNContext ctx = nullptr;
    if (wp::Failed(SUNContext_Create(SUN_COMM_NULL, &ctx), "SUNContext_Create")) return 1;
    int rc = 0;
    {
      fed::Scene s;
      fed::BuildScene(&s, ny);
      const double hs = fes::GuardStep(ctx, &s.prob, "G3_CD");
      if (c.damped) fed::SetDamping(&s, c.kind, 2 / hs);
      const double h = c.frac * hs;
      s.prob.nout = 1;
      s.prob.tend = h * static_cast<double>(steps);
      s.prob.ref.assign(1, s.prob.x0);
      wp::Outcome o;
      rc = c.hand ? fed::HandRun(&s, h, &o) : fes::CeodeRun(ctx, &s.prob, c.ce, h, &o);
      std::printf("%s: %d DOF, %ld steps, %ld f evals\n", c.name, s.plate.n, o.steps, o.rhs_evals);
    }
    SUNContext_Free(&ctx);
    return rc;
  }
  std::fprintf(stderr, "unknown configuration %s\n", argv[1]);
  return 2;
}
