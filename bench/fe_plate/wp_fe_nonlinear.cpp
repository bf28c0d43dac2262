// -----------------------------------------------------------------------------
// wp_fe_nonlinear: the Q4 cantilever with a large-deflection truss (README.md of this family).
// One axial spring along every element edge, force k_t (l - L) along the current edge direction;
// its linear stiffness is assembled into K, so f(x) = -M^{-1} (K x + N(x)) with N(x) = O(|x|^2).
// Start x0 = 0, v0 = A (w_1 phi_1 + 0.3 w_2 phi_2) (tip deflection A = 0.15); one period of
// mode 1, 20 outputs, errors relative to ||A (phi_1 + 0.3 phi_2)||_2.
// Reference: CEODE G7_O7 at 0.1 of its stable step, checked by its own convergence (runs at 0.4,
// 0.2, 0.1: observed order p and the error estimate d(0.2, 0.1) / (2^p - 1) <= 1e-8); the same
// run at amplitude 1e-3 A, scaled back, must differ by more than 1e-3 (f is nonlinear there).
// Curves: the hand loop (equal to CEODE G3_CD), CEODE G3_CD, G4_A34, G5_O4, G7_O7; CEODE error
// control (wp::FeTolCurves, config "<set> adaptive"); ARKODE ERK 3/4/5, CVODE Adams, CVODE BDF +
// SPGMR, ARKStep IMEX (K x implicit) and DIRK + SPGMR.
// Usage: wp_fe_nonlinear [--csv FILE] [--quick]. Exit code 0 when the modes and the reference
// converged, f is nonlinear, the hand loop equals G3_CD, G3_CD has order 2, every run succeeded.
// -----------------------------------------------------------------------------
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "fe_plate_model.h"
#include "fe_plate_modes.h"
#include "wp_common.h"

namespace {

using wp::Vec;

// The truss: edge list over free-DOF indices (-1: a clamped node).
struct Truss {
  std::vector<int> a, b;       // node DOF base (2 k) of the two ends, -1 if clamped
  std::vector<double> dx, dy;  // reference edge vector
  double kt = 0;               // axial stiffness k_t
};

struct Scene {
  fe::Plate plate;
  Truss truss;
  wp::Problem prob;
};

Truss MakeTruss(const fe::Plate& p, double kt) {
  Truss t;
  t.kt = kt;
  const double hx = p.Lx / p.nx, hy = p.Ly / p.ny;
  auto dof = [&p](int i, int j) { return i == 0 ? -1 : 2 * fe::NodeIndex(p, i, j); };
  for (int i = 0; i <= p.nx; ++i) {
    for (int j = 0; j <= p.ny; ++j) {
      if (i < p.nx) {
        t.a.push_back(dof(i, j));
        t.b.push_back(dof(i + 1, j));
        t.dx.push_back(hx);
        t.dy.push_back(0);
      }
      if (j < p.ny && i > 0) {
        t.a.push_back(dof(i, j));
        t.b.push_back(dof(i, j + 1));
        t.dx.push_back(0);
        t.dy.push_back(hy);
      }
    }
  }
  return t;
}

// F += the truss's internal force at x minus its linear part K_t x (K_t is in the plate's K,
// AddTrussStiffness): the nonlinear remainder N(x) = O(|x|^2).
void TrussRemainder(const Truss& t, const double* x, double* F) {
  const size_t ne = t.a.size();
  for (size_t e = 0; e < ne; ++e) {
    const int ia = t.a[e], ib = t.b[e];
    double du = 0, dv = 0;  // u_B - u_A
    if (ib >= 0) {
      du += x[ib];
      dv += x[ib + 1];
    }
    if (ia >= 0) {
      du -= x[ia];
      dv -= x[ia + 1];
    }
    const double ux = t.dx[e] + du, uy = t.dy[e] + dv;
    const double len0 = t.dx[e] + t.dy[e];  // one of the two is zero
    const double len = std::sqrt(ux * ux + uy * uy);
    const double s = t.kt * (len - len0) / len;
    const double lin = t.kt * (t.dx[e] * du + t.dy[e] * dv) / (len0 * len0);  // along the edge
    const double fx = s * ux - lin * t.dx[e], fy = s * uy - lin * t.dy[e];
    if (ib >= 0) {
      F[ib] += fx;
      F[ib + 1] += fy;
    }
    if (ia >= 0) {
      F[ia] -= fx;
      F[ia + 1] -= fy;
    }
  }
}

// K(r, c) += v; (r, c) is in the plate's 3 x 3 node stencil.
void AddEntry(fe::Plate* p, int r, int c, double v) {
  for (int q = p->rowptr[r]; q < p->rowptr[r + 1]; ++q) {
    if (p->col[q] == c) {
      p->val[q] += v;
      return;
    }
  }
}

// The truss's linear stiffness k_t e e^T per edge (e its unit direction) into the plate's K.
void AddTrussStiffness(const Truss& t, fe::Plate* p) {
  for (size_t e = 0; e < t.a.size(); ++e) {
    const int d = t.dx[e] != 0 ? 0 : 1;  // the component along the edge
    const int ends[2] = {t.a[e], t.b[e]};
    for (int i = 0; i < 2; ++i) {
      for (int j = 0; j < 2; ++j) {
        if (ends[i] < 0 || ends[j] < 0) continue;
        AddEntry(p, ends[i] + d, ends[j] + d, i == j ? t.kt : -t.kt);
      }
    }
  }
}

// a = -M^{-1} (K x + N(x)), K the plate's and the truss's linear stiffness.
int Accel(double, const double* x, const double*, double* a, void* user) {
  const Scene& s = *static_cast<const Scene*>(user);
  const fe::Plate& p = s.plate;
  fe::KTimes(p, x, a);
  TrussRemainder(s.truss, x, a);
  for (int k = 0; k < p.n; ++k) a[k] *= -p.invm[k];
  return 0;
}

// IMEX: implicit (x' = v, v' = -M^{-1} K x), linear; explicit v' = -M^{-1} N(x).
int RhsImplicit(sunrealtype, N_Vector y, N_Vector yd, void* user) {
  const auto* s = static_cast<const Scene*>(user);
  const int n = s->plate.n;
  const double* Y = N_VGetArrayPointer(y);
  double* D = N_VGetArrayPointer(yd);
  std::copy(Y + n, Y + 2 * static_cast<ptrdiff_t>(n), D);
  fe::Accel(s->plate, Y, D + n);
  return 0;
}

int RhsExplicit(sunrealtype, N_Vector y, N_Vector yd, void* user) {
  const auto* s = static_cast<const Scene*>(user);
  const fe::Plate& p = s->plate;
  const int n = p.n;
  const double* Y = N_VGetArrayPointer(y);
  double* D = N_VGetArrayPointer(yd);
  std::fill(D, D + 2 * static_cast<ptrdiff_t>(n), 0.0);
  TrussRemainder(s->truss, Y, D + n);
  for (int k = 0; k < n; ++k) D[n + k] *= -p.invm[k];
  return 0;
}

constexpr double kAmplitude = 0.15;
constexpr double kTrussStiffness = 0.05;  // k_t / (E thick): the plate carries most of the load

void BuildScene(Scene* s, double amplitude, const fe::Modes& md) {
  wp::Problem& p = s->prob;
  p.n = s->plate.n;
  p.user = s;
  p.Lift<Accel>();
  p.nout = 20;
  p.fe = RhsExplicit;
  p.fi = RhsImplicit;
  p.fi_linear = true;
  // Start undeformed with the modal velocities: N(x) then rises from zero like t^2 and the
  // high modes follow it quasi-statically. (Starting deformed, N(x0) is a step load that rings
  // every mode of the mesh: errors of 1e-5 that no method resolves at these steps.)
  p.x0.assign(p.n, 0.0);
  p.v0.resize(p.n);
  for (int k = 0; k < p.n; ++k) {
    p.v0[k] = amplitude * (md.w[0] * md.phi[0][k] + 0.3 * md.w[1] * md.phi[1][k]);
  }
  p.lumped_mass = s->plate.mass;
  Vec xs(p.n);  // the linear solution's amplitude: A (phi_1 + 0.3 phi_2)
  for (int k = 0; k < p.n; ++k) xs[k] = amplitude * (md.phi[0][k] + 0.3 * md.phi[1][k]);
  p.x0norm = wp::Norm2(xs);
  p.tend = 2 * M_PI / md.w[0];
}

double MaxRelDiff(const std::vector<Vec>& a, const std::vector<Vec>& b, double scale_b,
                  double norm) {
  double d = 0;
  for (size_t k = 0; k < a.size() && k < b.size(); ++k) {
    double e2 = 0;
    for (size_t i = 0; i < a[k].size(); ++i) {
      const double q = a[k][i] - scale_b * b[k][i];
      e2 += q * q;
    }
    d = std::max(d, std::sqrt(e2) / norm);
  }
  return d;
}

// The reference table (G7_O7 at 0.1 of its stable step) and its checks; returns failures.
int Reference(SUNContext ctx, Scene* s, const fe::Modes& md) {
  wp::Problem& p = s->prob;
  const double hs = wp::GuardStep(ctx, p, "G7_O7");
  const wp::CeodeOpts c("G7_O7");
  std::vector<Vec> x[3];
  const double frac[3] = {0.4, 0.2, 0.1};
  int bad = 0;
  for (int k = 0; k < 3; ++k) {
    wp::Outcome o;
    bad += wp::CeodeRun(ctx, p, c, frac[k] * hs, &o, nullptr, &x[k]);
  }
  const double d1 = MaxRelDiff(x[0], x[1], 1, p.x0norm);
  const double d2 = MaxRelDiff(x[1], x[2], 1, p.x0norm);
  const double order = std::log2(d1 / d2);
  const double est = order >= 1 ? d2 / (std::pow(2.0, order) - 1) : d2;
  const bool conv = bad == 0 && est <= 1e-8;
  std::printf(
      "reference G7_O7 at 0.1 h_s (h_s = %.6e): d(0.4, 0.2) = %.3e, d(0.2, 0.1) = %.3e, observed "
      "order %.2f, estimated error %.3e (<= 1e-8) %s\n",
      hs, d1, d2, order, est, conv ? "ok" : "-- NOT CONVERGED");
  p.ref = x[2];
  // Nonlinearity: the small-amplitude run, scaled back, against the A run (both at 0.2 h_s).
  Scene small;
  small.plate = s->plate;
  small.truss = s->truss;
  BuildScene(&small, kAmplitude * 1e-3, md);
  std::vector<Vec> xs;
  wp::Outcome o;
  bad += wp::CeodeRun(ctx, small.prob, c, 0.2 * hs, &o, nullptr, &xs);
  const double nl = MaxRelDiff(x[1], xs, 1e3, p.x0norm);
  std::printf(
      "nonlinearity: amplitude %.3g against %.3g scaled back: max relative difference %.3e "
      "(> 1e-3) %s\n",
      kAmplitude, kAmplitude * 1e-3, nl, nl > 1e-3 ? "ok" : "-- TOO LINEAR");
  return bad + !conv + !(nl > 1e-3);
}

int HandRun(Scene* s, double h_req, wp::Outcome* out) {
  return wp::LeapfrogRun(
      s->prob, h_req, [s](const double* x, double* a) { Accel(0, x, nullptr, a, s); }, out);
}

void CeodeCurves(SUNContext ctx, Scene* s, bool quick, wp::Rounds* rounds) {
  using V = std::vector<double>;
  const std::vector<wp::FracCurve> curves = {
      {"G3_CD", wp::CeodeOpts("G3_CD"), quick ? V{0.9, 0.45, 0.225} : V{0.9, 0.6, 0.4, 0.25, 0.12, 0.06}},
      {"G4_A34", wp::CeodeOpts("G4_A34"), quick ? V{0.9, 0.45} : V{0.9, 0.6, 0.4, 0.25}},
      {"G5_O4", wp::CeodeOpts("G5_O4"), quick ? V{0.9} : V{0.9, 0.6, 0.4}},
      {"G7_O7", wp::CeodeOpts("G7_O7"), quick ? V{0.9} : V{0.9, 0.6}}};
  wp::FractionCurves(ctx, &s->prob, curves, rounds,
                     [s](double hr, wp::Outcome* o) { return HandRun(s, hr, o); });
  wp::TolCurves(ctx, &s->prob,
                wp::FeTolCurves(wp::CeodeOpts(), "",
                                {"G3_CD", "G4_A34", "G5_O4", "G6_O5", "G7_O7", "G8_O8"}, quick),
                quick ? 0.3 : wp::kSundialsCutoff, rounds);
}

}  // namespace

int main(int argc, char** argv) {
  const wp::Args args = wp::ParseArgs(argc, argv);
  SUNContext ctx = nullptr;
  if (wp::Failed(SUNContext_Create(SUN_COMM_NULL, &ctx), "SUNContext_Create")) return 1;
  int bad = 0;
  {
    Scene s;
    s.plate = args.quick ? fe::MakePlate(16, 4) : fe::MakePlate(80, 20);  // 160 or 3 360 DOF
    s.truss = MakeTruss(s.plate, kTrussStiffness * s.plate.E * s.plate.thick);
    AddTrussStiffness(s.truss, &s.plate);
    const fe::Modes md = fe::LowestModes(s.plate, 2);
    bad += md.residual < 1e-9 ? 0 : 1;
    BuildScene(&s, kAmplitude, md);
    std::printf(
        "fe_nonlinear: Q4 cantilever %dx%d, %d DOF, with a large-deflection truss (%zu edges, "
        "k_t = %.3g); linearised w1 = %.6e, w2 = %.6e (modes residual %.2e); x0 = 0, v0 = %.2f "
        "(w1 phi1 + 0.3 w2 phi2), one period %.6e, %d outputs\n",
        s.plate.nx, s.plate.ny, s.plate.n, s.truss.a.size(), s.truss.kt, md.w[0], md.w[1],
        md.residual, kAmplitude, s.prob.tend, s.prob.nout);
    bad += Reference(ctx, &s, md);
    wp::Table table("fe_nonlinear", args.csv);
    wp::Rounds rounds(&table);
    CeodeCurves(ctx, &s, args.quick, &rounds);
    wp::FeSundialsCurves(ctx, &s.prob, wp::Sun::kImexSpgmr, wp::FeTols(args.quick),
                         args.quick ? 0.3 : wp::kSundialsCutoff, &rounds);
    rounds.Run();
    bad += wp::CheckSameMethod(table, "CEODE", "G3_CD", "CEODE-hand", "G3_CD", 1e-6) +
           wp::CheckSecondOrder(table, "G3_CD");
    wp::PrintEqualError(table, {1e-4, 1e-6});
    wp::PrintAdaptiveEqualError(table, {1e-4, 1e-6});
    bad += table.failures();
  }
  std::printf("%d problem(s)\n", bad);
  SUNContext_Free(&ctx);
  return bad == 0 ? 0 : 1;
}
