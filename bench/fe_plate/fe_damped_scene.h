// -----------------------------------------------------------------------------
// fe_damped_scene.h: the Rayleigh-damped FE plate, shared by
// wp_fe_damped_mass.cpp (C = a M: mass-proportional) and wp_fe_damped_stiff.cpp (C = b K:
// stiffness-proportional).
//
// The Q4 cantilever of bench/fe_plate_model.h, f = -M^{-1} (K x + C v), C = a M + b K,
// lumped M. Start x0 = phi_1 + 0.3 phi_2, v0 = 0; Rayleigh damping keeps the modes
// decoupled, so x(t) = phi_1 q_1(t) + 0.3 phi_2 q_2(t) with each q the closed-form
// damped oscillator (bench/fe_plate_modes.h): that is the reference. One period of
// mode 1, error = max over 20 output instants of ||x - x_ref||_2 / ||x0||_2.
//
// Mesh 80 x 20 (3 360 DOF; --quick 16 x 4). Curves (fixed steps as fractions of each set's
// undamped stable step h_s from the guard):
//  * CEODE-hand: the explicit central-difference loop a user writes for damping:
//    v_{n+1/2} = ((1 - a h/2) v_{n-1/2} - h M^{-1} K (x_n + b v_{n-1/2})) / (1 + a h/2),
//    x_{n+1} = x_n + h v_{n+1/2}: the mass term at the mean velocity (exact, diagonal),
//    the stiffness term at the lagged half-step velocity (as explicit FE codes do; its
//    step limit shrinks with b omega_max, and it is first order in b).
//  * CEODE with the velocity dependence declared: prediction-correction (CE_IMPLICIT_PC),
//    CE_IMPLICIT_AUTO (PC while its corrections contract by 5, else the nonlinear solver),
//    Newton with a matrix-free SPGMR on M - kappa df/dv (stiff variant: also at a loosened
//    Newton tolerance, 1e-7); G4_A34 and G5_O4 with AUTO (mass variant; with C = b K G4_A34
//    diverges at every step tried, printed by G4Probe); and (stiff variant) the undeclared,
//    lagged-velocity explicit step (first order, docs/theory.md 4.1).
//  * (stiff variant) Newton with the exact df/dv = -M^{-1} C (VelJac, CSR on K's pattern)
//    factored by KLU once per step size: G3_CD-Newton-KLU, G5_O4-Newton-KLU and the adaptive
//    G5_O4-KLU. The damping is linear and the matrix exact, so every step takes one Newton
//    iteration (one f, one KLU solve); the elastic force stays explicit, so the step is capped
//    at the undamped stable step 2/omega_max (ERK3's at about 0.67/omega_max), where G5_O4's
//    error is already about 2e-8.
//  * CEODE error control with AUTO and SPGMR (AdaptiveConfigs, wp::FeTolCurves): config
//    "<set>-AUTO adaptive", h_or_tol the tolerance.
//  * ARKODE ERK adaptive orders 3, 4, 5; CVODE Adams (fixed point); CVODE BDF + SPGMR;
//    ARKStep IMEX (damping -C v implicit and linear, K x explicit) + SPGMR; ARKStep
//    DIRK (all implicit) + SPGMR.
// Checks (exit 1): the modes converged, every run succeeded, the mass-proportional hand
// loop equals CEODE G3_CD with Newton (same method), CEODE G3_CD converges at order 2, and
// (stiff variant) G3_CD with KLU gives the errors of G3_CD with SPGMR at the same steps.
// -----------------------------------------------------------------------------
#ifndef CEODE_BENCH_FE_DAMPED_SCENE_H_
#define CEODE_BENCH_FE_DAMPED_SCENE_H_

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "fe_plate_model.h"
#include "fe_plate_modes.h"
#include "wp_common.h"

namespace fed {

using wp::Vec;

enum class Damping { kMass, kStiffness };

struct Scene {
  fe::Plate plate;
  fe::Modes modes;
  double amp2 = 0.3;
  wp::Problem prob;
};

inline int Accel(double, const double* x, const double* v, double* a, void* user) {
  fe::AccelDamped(static_cast<const Scene*>(user)->plate, x, v, a);
  return 0;
}

// df/dv = -M^{-1} C = -a I - b M^{-1} K in CSR on K's pattern (its diagonal included): the
// exact, constant Jacobian that KLU factors in the Newton matrix I - kappa df/dv.
inline int VelJac(sunrealtype, N_Vector, N_Vector, N_Vector, SUNMatrix J, void* user, N_Vector,
                  N_Vector, N_Vector) {
  const fe::Plate& p = static_cast<const Scene*>(user)->plate;
  sunindextype* rp = SUNSparseMatrix_IndexPointers(J);
  sunindextype* ci = SUNSparseMatrix_IndexValues(J);
  double* jv = SUNSparseMatrix_Data(J);
  for (int r = 0; r <= p.n; ++r) rp[r] = p.rowptr[r];
  for (int r = 0; r < p.n; ++r) {
    for (int q = p.rowptr[r]; q < p.rowptr[r + 1]; ++q) {
      ci[q] = p.col[q];
      jv[q] = -p.damp_k * p.invm[r] * p.val[q] - (p.col[q] == r ? p.damp_m : 0.0);
    }
  }
  return 0;
}

// IMEX: the elastic force explicit, the damping force -M^{-1} C v implicit (linear in y).
inline int RhsExplicit(sunrealtype, N_Vector y, N_Vector yd, void* user) {
  const auto* s = static_cast<const Scene*>(user);
  const int n = s->plate.n;
  const double* Y = N_VGetArrayPointer(y);
  double* D = N_VGetArrayPointer(yd);
  std::copy(Y + n, Y + 2 * n, D);
  fe::Accel(s->plate, Y, D + n);
  return 0;
}

inline int RhsImplicit(sunrealtype, N_Vector y, N_Vector yd, void* user) {
  const auto* s = static_cast<const Scene*>(user);
  const fe::Plate& p = s->plate;
  const int n = p.n;
  const double* V = N_VGetArrayPointer(y) + n;
  double* D = N_VGetArrayPointer(yd);
  std::fill(D, D + n, 0.0);
  if (p.damp_k != 0) {
    fe::Accel(p, V, D + n);  // -M^{-1} K v
    for (int k = 0; k < n; ++k) D[n + k] *= p.damp_k;
  } else {
    std::fill(D + n, D + 2 * n, 0.0);
  }
  for (int k = 0; k < n; ++k) D[n + k] -= p.damp_m * V[k];
  return 0;
}

// The plate of 4 ny x ny square elements, its two lowest modes and the undamped problem.
inline void BuildScene(Scene* s, int ny) {
  s->plate = fe::MakePlate(4 * ny, ny);
  s->modes = fe::LowestModes(s->plate, 2);
  const double w1 = s->modes.w[0];
  wp::Problem& p = s->prob;
  p.n = s->plate.n;
  p.user = s;
  p.Lift<Accel>();
  p.nout = 20;
  p.fe = RhsExplicit;
  p.fi = RhsImplicit;
  p.fi_linear = true;
  p.vjac = VelJac;  // used by the KLU curves only (the SPGMR curves are matrix-free)
  p.vjac_nnz = static_cast<long>(s->plate.val.size());
  p.x0.resize(p.n);
  for (int k = 0; k < p.n; ++k) p.x0[k] = s->modes.phi[0][k] + s->amp2 * s->modes.phi[1][k];
  p.v0.assign(p.n, 0.0);
  p.lumped_mass = s->plate.mass;
  p.x0norm = wp::Norm2(p.x0);
  p.tend = 2 * M_PI / w1;
}

// Rayleigh coefficients: 5 % of critical in mode 1 (mass), or b such that the top
// mode has zeta = 2 (stiffness: the damping structural codes add against high-frequency
// noise; mode 1 then has zeta = omega_1 / omega_max * 2).
inline void SetDamping(Scene* s, Damping kind, double omega_max) {
  wp::Problem& p = s->prob;
  if (kind == Damping::kMass) {
    s->plate.damp_m = 2 * 0.05 * s->modes.w[0];
    p.vel_diag.assign(p.n, -s->plate.damp_m);  // f = M^{-1} (-K x) - damp_m x': affine in x'
  } else {
    s->plate.damp_k = 2 * 2.0 / omega_max;
    p.vel_diag.clear();
  }
  p.ref.clear();
  const double z1 = fe::RayleighZeta(s->plate, s->modes.w[0]);
  const double z2 = fe::RayleighZeta(s->plate, s->modes.w[1]);
  for (int k = 1; k <= p.nout; ++k) {
    const double t = wp::OutputTime(p, k);
    const double q1 = fe::DampedModeResponse(s->modes.w[0], z1, t);
    const double q2 = s->amp2 * fe::DampedModeResponse(s->modes.w[1], z2, t);
    Vec x(p.n);
    for (int i = 0; i < p.n; ++i) x[i] = q1 * s->modes.phi[0][i] + q2 * s->modes.phi[1][i];
    p.ref.push_back(x);
  }
}

// The explicit central-difference loop with damping (see the header comment).
inline int HandRun(Scene* s, double h_req, wp::Outcome* out) {
  const fe::Plate& p = s->plate;
  const wp::Problem& pr = s->prob;
  const int n = p.n;
  const long m = wp::StepsPerOutput(pr, h_req);
  const double h = wp::FixedStep(pr, h_req);
  const double am = p.damp_m, bk = p.damp_k;
  const double c0 = (1 - 0.5 * am * h) / (1 + 0.5 * am * h), c1 = h / (1 + 0.5 * am * h);
  Vec x(pr.x0), v(n), a(n), w(n);
  fe::AccelDamped(p, x.data(), pr.v0.data(), a.data());
  for (int k = 0; k < n; ++k) v[k] = pr.v0[k] + 0.5 * h * a[k];  // v_{1/2}
  for (int k = 0; k < n; ++k) x[k] += h * v[k];
  wp::Track tr(pr);
  long steps = 1;
  for (int o = 1; o <= pr.nout; ++o) {
    for (long j = (o == 1 ? 1 : 0); j < m; ++j, ++steps) {
      if (bk != 0) {
        for (int k = 0; k < n; ++k) w[k] = x[k] + bk * v[k];
        fe::Accel(p, w.data(), a.data());
      } else {
        fe::Accel(p, x.data(), a.data());
      }
      for (int k = 0; k < n; ++k) {
        v[k] = c0 * v[k] + c1 * a[k];
        x[k] += h * v[k];
      }
    }
    tr.Output(o, x.data());
  }
  out->steps = steps;
  out->rhs_evals = steps;
  return tr.Finish(false, out);
}

inline void HandCurve(Scene* s, const std::vector<double>& frac, double hs, wp::Rounds* rounds) {
  for (double f : frac) {
    const double hr = f * hs;
    const double h = wp::FixedStep(s->prob, hr);
    rounds->Measure("CEODE-hand", "CD-damped", h,
                    [s, hr](wp::Outcome* o) { return HandRun(s, hr, o); });
  }
}

// Per-step time of one curve at its first row (seconds / steps).
inline double NsPerStep(const wp::Table& t, const std::string& solver, const std::string& config) {
  for (const wp::Row& r : t.rows()) {
    if (r.solver == solver && r.config == config && r.steps > 0) return 1e9 * r.seconds / r.steps;
  }
  return 0;
}

// The exact, constant df/dv (VelJac) factored by KLU (AMD ordering): the Newton matrix
// I - kappa df/dv is formed and factored once per step size (CEodeSetJacEvalFrequency beyond the
// run's steps); the Newton tolerance of the loosened SPGMR curve.
inline wp::CeodeOpts KluOpts(const char* set) {
  wp::CeodeOpts c(set);
  c.vel = true;
  c.ls = wp::CeodeOpts::kKlu;
  c.msbj = 1L << 30;
  c.nls_rtol = 1e-7;
  c.nls_atol = 1e-2 * c.nls_rtol;  // |a| ~ 1e-2
  return c;
}

// Fewer points for the costly curves: a few minutes per scene.
inline std::vector<wp::FracCurve> CeodeConfigs(Damping kind, bool quick) {
  using V = std::vector<double>;
  const V f_cd = quick ? V{0.9, 0.45, 0.225} : V{0.9, 0.6, 0.4, 0.25, 0.12, 0.06};
  const V f_few = quick ? V{0.9, 0.45, 0.225} : V{0.9, 0.6, 0.4, 0.25};
  wp::CeodeOpts pc, autom, newton;
  pc.vel = autom.vel = newton.vel = true;
  pc.implicit_mode = CE_IMPLICIT_PC;
  pc.ls = wp::CeodeOpts::kNone;  // PC never solves; without a solver Newton is a fixed point
  autom.implicit_mode = CE_IMPLICIT_AUTO;
  autom.ls = newton.ls = wp::CeodeOpts::kSpgmr;  // matrix-free on M - kappa df/dv
  wp::CeodeOpts a34 = autom, o4 = autom;
  a34.method = "G4_A34";
  o4.method = "G5_O4";
  if (kind == Damping::kMass) {
    // CEodeSetVelJacDiagonal: C = damp_m M, so df/dx' = -damp_m, the exact solve in one f.
    wp::CeodeOpts diag = pc, diag_o4 = pc;
    diag.diagonal = diag_o4.diagonal = true;
    diag_o4.method = "G5_O4";
    return {{"G3_CD-AUTO", autom, f_cd},
            {"G3_CD-diag", diag, f_cd},
            {"G5_O4-diag", diag_o4, quick ? V{0.9} : V{0.9, 0.6, 0.4}},
            {"G3_CD-PC", pc, quick ? V{0.9, 0.45} : V{0.9, 0.4, 0.12}},
            {"G3_CD-Newton-SPGMR", newton, quick ? V{0.9, 0.45, 0.225} : V{0.9, 0.6, 0.4}},
            {"G4_A34-AUTO", a34, f_few},
            {"G5_O4-AUTO", o4, quick ? V{0.9} : V{0.9, 0.6, 0.4}}};
  }
  // The Newton tolerance is CEODE's 1e-12 by default; a user at 1e-4 .. 1e-6 can loosen it.
  wp::CeodeOpts loose = newton;
  loose.nls_rtol = 1e-7;
  loose.nls_atol = 1e-2 * loose.nls_rtol;  // |a| ~ 1e-2
  wp::CeodeOpts lag;  // velocity dependence declared absent: f sees the lagged velocity
  // G4_A34 diverges here at every step tried: G4Probe shows it, untimed. AUTO takes Newton here
  // (kappa |df/dv| = 3.6 at 0.9 h_s): the same numbers as a forced Newton curve, not run again.
  // The KLU curves: one Newton iteration per step (the problem is linear and the matrix exact);
  // G5_O4 at 0.9 h_s is already below 1e-7, so smaller steps only cost time.
  return {{"G3_CD-AUTO", autom, quick ? V{0.9} : V{0.9, 0.6}},
          {"G3_CD-Newton-SPGMR-rtol1e-7", loose, quick ? f_cd : V{0.9, 0.6, 0.4, 0.25, 0.12}},
          {"G3_CD-Newton-KLU", KluOpts("G3_CD"), quick ? V{0.9} : V{0.9, 0.6}},
          {"G5_O4-Newton-KLU", KluOpts("G5_O4"), quick ? V{0.9} : V{0.9, 0.6}},
          {"G3_CD-lagged", lag, quick ? V{0.1, 0.05} : V{0.1, 0.05, 0.025}}};
}

// CEODE's error control with the velocity dependence declared, the implicit step at the
// library's default (AUTO) with the matrix-free SPGMR of the fixed-step AUTO curves. With C = b K
// G4_A34 is left out (it diverges, G4Probe), and --quick keeps G5_O4 only: there every run's
// SPGMR products make up most of its f evaluations (11 000 of 11 600 at 1e-3 on the quick mesh).
inline std::vector<wp::TolCurve> AdaptiveConfigs(Damping kind, bool quick) {
  wp::CeodeOpts autom;
  autom.vel = true;
  autom.implicit_mode = CE_IMPLICIT_AUTO;
  autom.ls = wp::CeodeOpts::kSpgmr;
  std::vector<const char*> sets = {"G3_CD", "G4_A34", "G5_O4", "G6_O5", "G7_O7", "G8_O8"};
  if (kind == Damping::kStiffness) sets = {"G3_CD", "G5_O4", "G6_O5", "G7_O7", "G8_O8"};
  if (kind == Damping::kStiffness && quick) sets = {"G5_O4"};
  std::vector<wp::TolCurve> curves = wp::FeTolCurves(autom, "-AUTO", sets, quick);
  // G5_O4 with KLU: the step sits at the stable-step cap at every tolerance up to 1e-8, so two
  // tolerances show it; the matrix is refactored when the cap moves h (linear-solver setups).
  if (kind == Damping::kStiffness) {
    curves.push_back({"G5_O4-KLU adaptive", KluOpts("G5_O4"),
                      quick ? std::vector<double>{1e-6} : std::vector<double>{1e-4, 1e-6}});
  }
  return curves;
}

// G4_A34 with stiffness-proportional damping declared (zeta = 2 at the top): how far one
// period gets at fractions of its undamped stable step. Shown, not timed, not a check.
inline void G4Probe(SUNContext ctx, Scene* s) {
  wp::CeodeOpts c("G4_A34");
  c.vel = true;
  c.ls = wp::CeodeOpts::kSpgmr;
  const double hs = wp::GuardStep(ctx, s->prob, c.method);
  for (double f : {0.45, 0.1, 0.02}) {
    wp::Outcome o;
    const int rc = wp::CeodeRun(ctx, s->prob, c, f * hs, &o);
    std::printf("G4_A34 (Newton-SPGMR) at %.2f x its undamped stable step: %s (error %.3e)\n", f,
                rc != 0 ? "stopped (CE_UNSTABLE)" : "ran", o.error);
  }
}

inline std::vector<double> HandFractions(Damping kind, bool quick) {
  // The stiffness term at v_{n-1/2}: stable below h_s (sqrt(1 + z^2) - z), z = 2 at the top.
  if (kind == Damping::kStiffness) {
    return quick ? std::vector<double>{0.2, 0.1, 0.05} : std::vector<double>{0.2, 0.12, 0.06, 0.03};
  }
  return quick ? std::vector<double>{0.9, 0.45, 0.225}
               : std::vector<double>{0.9, 0.6, 0.4, 0.25, 0.12, 0.06};
}

inline int Checks(const wp::Table& table, Damping kind) {
  int bad = 0;
  if (kind == Damping::kMass) {
    // Newton solves the diagonal step exactly: the same method as the hand loop.
    bad +=
        wp::CheckSameMethod(table, "CEODE", "G3_CD-Newton-SPGMR", "CEODE-hand", "CD-damped", 1e-6);
  }
  const std::vector<const char*> fitted =
      kind == Damping::kMass ? std::vector<const char*>{"G3_CD-AUTO", "G3_CD-Newton-SPGMR"}
                             : std::vector<const char*>{"G3_CD-Newton-SPGMR-rtol1e-7"};
  for (const char* c : fitted) bad += wp::CheckSecondOrder(table, c);
  if (kind == Damping::kStiffness) {
    // KLU (exact matrix) and SPGMR (difference-quotient products) solve the same G3_CD step to
    // the same Newton tolerance (1e-7 relative): the errors agree to 1e-3 relative at the
    // shared steps (measured: 1.2e-4).
    bad += wp::CheckSameMethod(table, "CEODE", "G3_CD-Newton-KLU", "CEODE",
                               "G3_CD-Newton-SPGMR-rtol1e-7", 1e-3);
  }
  return bad;
}

inline int DampedMain(int argc, char** argv, Damping kind, const char* scene) {
  const wp::Args args = wp::ParseArgs(argc, argv);
  SUNContext ctx = nullptr;
  if (wp::Failed(SUNContext_Create(SUN_COMM_NULL, &ctx), "SUNContext_Create")) return 1;
  int bad = 0;
  {
    Scene s;
    BuildScene(&s, args.quick ? 4 : 20);                    // 160 or 3 360 DOF
    const double hs = wp::GuardStep(ctx, s.prob, "G3_CD");  // undamped: f ignores v here
    const double omega_max = 2 / hs;
    SetDamping(&s, kind, omega_max);
    bad += s.modes.residual < 1e-9 ? 0 : 1;
    const double z1 = fe::RayleighZeta(s.plate, s.modes.w[0]);
    const double zt = fe::RayleighZeta(s.plate, omega_max);
    std::printf(
        "%s: Q4 cantilever %dx%d, %d DOF, C = %.4e M + %.4e K; w1 = %.6e, w2 = %.6e, guard "
        "omega_max = %.6e (G3_CD h_s = %.6e); zeta: mode 1 %.4e, mode 2 %.4e, top %.4e; "
        "modes residual %.2e; one period %.6e, %d outputs\n",
        scene, s.plate.nx, s.plate.ny, s.plate.n, s.plate.damp_m, s.plate.damp_k, s.modes.w[0],
        s.modes.w[1], omega_max, hs, z1, fe::RayleighZeta(s.plate, s.modes.w[1]), zt,
        s.modes.residual, s.prob.tend, s.prob.nout);
    wp::Table table(scene, args.csv);
    wp::Rounds rounds(&table);
    HandCurve(&s, HandFractions(kind, args.quick), hs, &rounds);
    wp::FractionCurves(ctx, &s.prob, CeodeConfigs(kind, args.quick), &rounds);
    wp::TolCurves(ctx, &s.prob, AdaptiveConfigs(kind, args.quick),
                  args.quick ? 0.3 : wp::kSundialsCutoff, &rounds);
    wp::FeSundialsCurves(ctx, &s.prob, wp::Sun::kImexSpgmr, wp::FeTols(args.quick),
                         args.quick ? 0.3 : wp::kSundialsCutoff, &rounds);
    rounds.Run();
    if (kind == Damping::kStiffness) G4Probe(ctx, &s);
    bad += Checks(table, kind);
    wp::PrintEqualError(table, {1e-3, 1e-4, 1e-6});
    wp::PrintAdaptiveEqualError(table, {1e-3, 1e-4, 1e-6});
    const double hand = NsPerStep(table, "CEODE-hand", "CD-damped");
    std::printf("\nper-step time at the first row of each curve (ns/step; CPU clock, one run):\n");
    for (const char* c :
         {"G3_CD-AUTO", "G3_CD-PC", "G3_CD-Newton-SPGMR", "G3_CD-Newton-SPGMR-rtol1e-7",
          "G3_CD-Newton-KLU", "G5_O4-Newton-KLU", "G3_CD-lagged"}) {
      const double t = NsPerStep(table, "CEODE", c);
      if (t > 0)
        std::printf("  CEODE %-20s %10.1f  (%.3f x hand loop %.1f)\n", c, t, t / hand, hand);
    }
    bad += table.failures();
  }
  std::printf("%d problem(s)\n", bad);
  SUNContext_Free(&ctx);
  return bad == 0 ? 0 : 1;
}

}  // namespace fed

#endif  // CEODE_BENCH_FE_DAMPED_SCENE_H_
