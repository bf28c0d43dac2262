// -----------------------------------------------------------------------------
// wp_fe_plate: the linear Q4 cantilever plate (README.md of this family).
// Part 1, the stable step: the exact omega_max (Eigen, dense, on M^{-1/2} K M^{-1/2}) against the
// guard's Lanczos estimate, the Gershgorin bound and the element-by-element bound of explicit FE
// codes; the estimate within 2 % of the exact limit, both bounds never below omega_max.
// Part 2, work-precision at equal error against the exact two-mode solution: the hand loop,
// CEODE G3_CD, G4_A34, G5_O4 at fractions of the stable step (G5, weakly unstable, as an untimed
// probe), CEODE error control (wp::FeTolCurves), ARKODE ERK 3/4/5, CVODE Adams, CVODE BDF +
// SPGMR / + KLU, ARKStep DIRK + SPGMR.
// Part 3, scaling: time per step and DOF of the hand loop and CEODE from 10^4 to 10^6 DOF and the
// log-log slope, written to <csv>_scaling.csv.
// Usage: wp_fe_plate [--csv FILE] [--quick]
//        wp_fe_plate --count SOLVER NY STEPS (one untimed run, for callgrind: see CountMain)
// Exit code 0 when the modes converged, the stable-step criteria hold, the hand loop reproduces
// CEODE G3_CD, G3_CD converges at order 2, and every run succeeded. Never on a timing.
// -----------------------------------------------------------------------------
#include <ceode/ceode_stability.h>

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include "fe_plate_model.h"
#include "fe_plate_modes.h"
#include "wp_common.h"

namespace {

using Vec = std::vector<double>;

// ------------------------------------------------------------------ the scene
struct Scene {
  fe::Plate plate;
  double w1 = 0, w2 = 0, amp2 = 0.3;
  Vec phi1, phi2;  // M-normalised, then phi1 scaled to max |.| = 1 (phi2 alike)
  wp::Problem p;  // what the runners see: f, start, outputs, reference
};

int Accel(double, const double* x, const double*, double* a, void* user) {
  fe::Accel(static_cast<const Scene*>(user)->plate, x, a);
  return 0;
}

// J = [[0, I], [-M^{-1} K, 0]] of the first-order form, CSR.
int Jac1(sunrealtype, N_Vector, N_Vector, SUNMatrix J, void* user, N_Vector, N_Vector, N_Vector) {
  const auto* s = static_cast<const Scene*>(user);
  const fe::Plate& p = s->plate;
  sunindextype* rp = SUNSparseMatrix_IndexPointers(J);
  sunindextype* ci = SUNSparseMatrix_IndexValues(J);
  double* v = SUNSparseMatrix_Data(J);
  sunindextype q = 0;
  for (int r = 0; r < p.n; ++r) {
    rp[r] = q;
    ci[q] = p.n + r;
    v[q++] = 1;
  }
  for (int r = 0; r < p.n; ++r) {
    rp[p.n + r] = q;
    for (int k = p.rowptr[r]; k < p.rowptr[r + 1]; ++k) {
      ci[q] = p.col[k];
      v[q++] = -p.invm[r] * p.val[k];
    }
  }
  rp[2 * static_cast<ptrdiff_t>(p.n)] = q;
  return 0;
}

// x(t) = phi_1 cos(w_1 t) + amp2 phi_2 cos(w_2 t)
Vec Exact(const Scene& s, double t) {
  Vec x(s.plate.n);
  const double c1 = std::cos(s.w1 * t), c2 = s.amp2 * std::cos(s.w2 * t);
  for (int k = 0; k < s.plate.n; ++k) x[k] = c1 * s.phi1[k] + c2 * s.phi2[k];
  return x;
}

void InitialState(const Scene& s, double* x) {
  for (int k = 0; k < s.plate.n; ++k) x[k] = s.phi1[k] + s.amp2 * s.phi2[k];
}

// ------------------------------------------------------ the reference modes
// The two lowest modes (bench/fe_plate_modes.h); returns the largest relative residual
// ||K phi - w^2 M phi|| / ||K phi||.
double LowestModes(Scene* s) {
  const fe::Plate& p = s->plate;
  const fe::Modes md = fe::LowestModes(p, 2);
  s->w1 = md.w[0];
  s->w2 = md.w[1];
  s->phi1 = md.phi[0];
  s->phi2 = md.phi[1];
  return md.residual;
}

// The runners' view of the scene (the modes known): one period of mode 1, 20 outputs with the
// exact solution at each.
void FillProblem(Scene* s) {
  wp::Problem& q = s->p;
  const fe::Plate& p = s->plate;
  q.n = p.n;
  q.user = s;
  q.Lift<Accel>();
  q.f1_linear = true;
  q.jac1 = Jac1;
  q.jac_nnz = p.n + static_cast<long>(p.val.size());
  q.x0.resize(p.n);
  InitialState(*s, q.x0.data());
  q.v0.assign(p.n, 0.0);
  q.lumped_mass = p.mass;
  q.tend = 2 * M_PI / s->w1;
  q.nout = 20;
  q.ref.clear();
  for (int k = 1; k <= q.nout; ++k) q.ref.push_back(Exact(*s, wp::OutputTime(q, k)));
  q.x0norm = wp::Norm2(q.x0);
}

// ------------------------------------------------------------ the stable step
struct StepFigures {
  double exact = 0, estimate = 0, gershgorin = 0, element = 0;
  long guard_fe = 0;
};

// Largest frequency of one Q4 element with its lumped nodal mass, unconstrained.
double ElementBound(const fe::Plate& p) {
  Eigen::Matrix<double, 8, 8> k;
  for (int i = 0; i < 8; ++i) {
    for (int j = 0; j < 8; ++j) k(i, j) = p.ke[i][j];
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 8, 8>> es(k / p.me);
  return std::sqrt(es.eigenvalues().maxCoeff());
}

double ExactOmegaMax(const fe::Plate& p) {
  Eigen::MatrixXd A = Eigen::MatrixXd(fe::StiffnessSparse(p));
  Eigen::VectorXd s(p.n);
  for (int k = 0; k < p.n; ++k) s(k) = 1 / std::sqrt(p.mass[k]);
  A = s.asDiagonal() * A * s.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(A, Eigen::EigenvaluesOnly);
  return std::sqrt(es.eigenvalues().maxCoeff());
}

// The guard's estimate (CEodeGetStableStep at safety 1 gives Omega_max / omega_est)
// and the Gershgorin bound through the public API, on a CEODE memory of the scene.
bool ApiFigures(SUNContext ctx, Scene* s, StepFigures* f) {
  const fe::Plate& p = s->plate;
  wp::CeodeObjects o;
  if (!o.Create(ctx, s->p)) return false;
  N_Vector m = o.m = N_VNew_Serial(p.n, ctx);
  SUNMatrix K = SUNSparseMatrix(p.n, p.n, static_cast<sunindextype>(p.val.size()), CSR_MAT, ctx);
  if (m == nullptr || K == nullptr) return false;
  std::copy(p.mass.begin(), p.mass.end(), N_VGetArrayPointer(m));
  std::copy(p.rowptr.begin(), p.rowptr.end(), SUNSparseMatrix_IndexPointers(K));
  std::copy(p.col.begin(), p.col.end(), SUNSparseMatrix_IndexValues(K));
  std::copy(p.val.begin(), p.val.end(), SUNSparseMatrix_Data(K));
  sunrealtype hmax = 0, lim = 0;
  int deg = 0;
  sunrealtype par[8];
  long nme = 0, nls = 0;
  const bool ok =
      !wp::Failed(CEodeInit(o.mem, s->p.f2, 0, o.x, o.v), "CEodeInit") &&
      !wp::Failed(CEodeSetUserData(o.mem, s), "CEodeSetUserData") &&
      !wp::Failed(CEodeSetMethodByName(o.mem, "G3_CD"), "CEodeSetMethodByName") &&
      !wp::Failed(CEodeSetGuardMass(o.mem, m), "CEodeSetGuardMass") &&
      !wp::Failed(CEodeGetStableStep(o.mem, 1, &hmax), "CEodeGetStableStep") &&
      !wp::Failed(CEodeGetGuardStats(o.mem, &f->guard_fe, &nme, &nls), "CEodeGetGuardStats") &&
      !wp::Failed(CEodeGetFrequencyBound(o.mem, K, m, &f->gershgorin), "CEodeGetFrequencyBound") &&
      !wp::Failed(CEodeGetMethodParams("G3_CD", &deg, par, 8), "CEodeGetMethodParams") &&
      !wp::Failed(CEodeStabilityLimit(deg, par, 0, &lim), "CEodeStabilityLimit");
  f->estimate = ok && hmax > 0 ? lim / hmax : 0;
  f->element = ElementBound(p);
  SUNMatDestroy(K);
  return ok;
}

// Prints one model's figures; returns the number of failed criteria.
int ReportStep(const char* label, const StepFigures& f) {
  std::printf("%-28s omega_max: ", label);
  int bad = 0;
  if (f.exact > 0) {
    const double de = 100 * (f.estimate / f.exact - 1);
    std::printf(
        "exact %.6e, guard estimate %.6e (%+.3f %%, %ld f evals), Gershgorin %.6e "
        "(%+.2f %%), element %.6e (%+.2f %%)\n",
        f.exact, f.estimate, de, f.guard_fe, f.gershgorin, 100 * (f.gershgorin / f.exact - 1),
        f.element, 100 * (f.element / f.exact - 1));
    // The stable step's criterion: the estimate's limit within 2 %, the bounds never below.
    bad += !(std::fabs(de) <= 2.0) + !(f.gershgorin >= f.exact) + !(f.element >= f.exact);
  } else {
    std::printf(
        "guard estimate %.6e (%ld f evals), Gershgorin %.6e (%+.2f %% of the estimate), "
        "element %.6e (%+.2f %%)\n",
        f.estimate, f.guard_fe, f.gershgorin, 100 * (f.gershgorin / f.estimate - 1), f.element,
        100 * (f.element / f.estimate - 1));
    bad += !(f.gershgorin >= f.estimate * (1 - 1e-3)) + !(f.element >= f.estimate * (1 - 1e-3));
  }
  return bad;
}

int StableStepPart(SUNContext ctx, bool quick, Scene* wp_scene) {
  std::printf("\n== stable step ==\n");
  Scene small;
  small.plate = quick ? fe::MakePlate(12, 3) : fe::MakePlate(40, 10);
  LowestModes(&small);
  FillProblem(&small);
  StepFigures fs;
  fs.exact = ExactOmegaMax(small.plate);
  int bad = ApiFigures(ctx, &small, &fs) ? 0 : 1;
  char label[64];
  std::snprintf(label, sizeof label, "%dx%d mesh (%d DOF)", small.plate.nx, small.plate.ny,
                small.plate.n);
  bad += ReportStep(label, fs);
  StepFigures fw;
  bad += ApiFigures(ctx, wp_scene, &fw) ? 0 : 1;
  std::snprintf(label, sizeof label, "%dx%d mesh (%d DOF)", wp_scene->plate.nx, wp_scene->plate.ny,
                wp_scene->plate.n);
  bad += ReportStep(label, fw);
  std::printf("stable-step criteria: %s\n", bad == 0 ? "met" : "NOT MET");
  return bad;
}

// The hand-written central-differences loop on the same f (wp::LeapfrogRun).
int HandRun(Scene* s, double h_req, wp::Outcome* out) {
  const fe::Plate& p = s->plate;
  return wp::LeapfrogRun(
      s->p, h_req, [&p](const double* x, double* a) { fe::Accel(p, x, a); }, out);
}

struct WpResult {
  int bad = 0;
  double h_cd = 0;  // G3_CD's stable step
};

// G3_CD (and the hand loop) down to 1e-6, which takes a step 15 times below its limit.
void CeodeCurves(SUNContext ctx, Scene* s, wp::Rounds* rounds, bool quick, WpResult* res) {
  using V = std::vector<double>;
  const V frac_cd = quick ? V{0.99, 0.5, 0.25} : V{0.99, 0.7, 0.5, 0.35, 0.25, 0.12, 0.06};
  const V frac_high = quick ? V{0.99, 0.5} : V{0.99, 0.7, 0.5, 0.35, 0.25};
  const std::vector<wp::FracCurve> curves = {{"G3_CD", wp::CeodeOpts("G3_CD"), frac_cd},
                                             {"G4_A34", wp::CeodeOpts("G4_A34"), frac_high},
                                             {"G5_O4", wp::CeodeOpts("G5_O4"), frac_high}};
  res->h_cd = wp::FractionCurves(ctx, &s->p, curves, rounds,
                                 [s](double hr, wp::Outcome* o) { return HandRun(s, hr, o); });
  wp::TolCurves(ctx, &s->p,
                wp::FeTolCurves(wp::CeodeOpts(), "",
                                {"G3_CD", "G4_A34", "G5_O4", "G6_O5", "G7_O7", "G8_O8"}, quick),
                quick ? 0.3 : wp::kSundialsCutoff, rounds);
}

// G5 is weakly unstable for every step (CEodeStabilityLimit = 0): its fastest mode
// grows from round-off. Shown, not timed: how far one period gets at small steps.
void G5Probe(SUNContext ctx, Scene* s, double h_cd) {
  for (double f : {0.3, 0.1}) {
    wp::Outcome o;
    const int rc = wp::CeodeRun(ctx, s->p, "G5", f * h_cd, &o);
    std::printf("G5 at h = %.2f x the G3_CD stable step: %s (error %.3e, %ld steps)\n", f,
                rc != 0 ? "stopped or non-finite (CE_UNSTABLE)" : "ran", o.error, o.steps);
  }
}

WpResult WorkPrecisionPart(SUNContext ctx, Scene* s, const wp::Args& args) {
  WpResult res;
  std::printf(
      "\n== work-precision: %dx%d Q4 mesh, %d DOF, w1 = %.6e, w2 = %.6e, one period "
      "(%.6e), %d outputs ==\n",
      s->plate.nx, s->plate.ny, s->plate.n, s->w1, s->w2, s->p.tend, s->p.nout);
  wp::Table table("fe_plate", args.csv);
  wp::Rounds rounds(&table);
  CeodeCurves(ctx, s, &rounds, args.quick, &res);
  G5Probe(ctx, s, res.h_cd);
  // KLU: the linear plate's Jacobian is constant and sparse.
  wp::FeSundialsCurves(
      ctx, &s->p, wp::Sun::kBdfKlu,
      args.quick ? std::vector<double>{1e-5} : std::vector<double>{1e-3, 1e-4, 1e-5, 1e-6, 1e-7},
      args.quick ? 0.3 : wp::kSundialsCutoff, &rounds);
  rounds.Run();
  // G3_CD and the hand loop are the same method; G3_CD converges at order 2.
  res.bad += wp::CheckSameMethod(table, "CEODE", "G3_CD", "CEODE-hand", "G3_CD", 1e-6) +
             wp::CheckSecondOrder(table, "G3_CD");
  wp::PrintEqualError(table, {1e-4, 1e-6});
  wp::PrintAdaptiveEqualError(table, {1e-4, 1e-6});
  res.bad += table.failures();
  return res;
}

// ----------------------------------------------------------------- scaling
struct ScalePoint {
  int n;
  double hand, cd, a34, o4;  // seconds per step
};

// Seconds per step of one solver: (T(2S) - T(S)) / S, so that creation, the start
// and the allocations are not counted (each T by the median rule). A failed run
// gives NaN; on a loaded machine the difference can come out <= 0, which is timing
// noise, reported as such and never a failure (timings do not decide pass/fail).
double PerStep(const std::function<int(Scene*, wp::Outcome*)>& run, Scene* s, double h,
               long steps) {
  wp::Outcome o;
  double t[2];
  for (int k = 0; k < 2; ++k) {
    s->p.tend = h * static_cast<double>((k + 1) * steps);
    t[k] = wp::TimeMedian([&]() { return run(s, &o); });
    if (t[k] < 0 || o.steps != (k + 1) * steps) return std::nan("");
  }
  return (t[1] - t[0]) / static_cast<double>(steps);
}

constexpr int kScaleRounds = 3;

// The solvers of the scaling part, each at its own fraction of G3_CD's step (inside its limit).
constexpr const char* kScaleSets[3] = {"G3_CD", "G4_A34", "G5_O4"};
constexpr double kScaleFrac[3] = {1.0, 0.8, 0.95};

// The scaling scene on one mesh of 4 ny x ny square elements: a smooth start, no reference
// (the modes are not needed, the error is not looked at).
void MakeScaleScene(int ny, Scene* s) {
  s->plate = fe::MakePlate(4 * ny, ny);
  const int n = s->plate.n;
  s->p.n = n;
  s->p.user = s;
  s->p.Lift<Accel>();
  s->p.x0.assign(n, 0.0);
  const int pairs = n / 2;
  for (int j = 0; 2 * j + 1 < n; ++j) s->p.x0[2 * j + 1] = 1e-3 * (j + 1.0) / pairs;
  s->p.v0.assign(n, 0.0);
  s->p.nout = 1;
}

// One mesh of 4 ny x ny square elements; h_cd is G3_CD's stable step on square
// elements of size dx_ref (the stable step scales with the element size).
ScalePoint ScaleAt(SUNContext ctx, int ny, double h_cd, double dx_ref) {
  Scene s;
  MakeScaleScene(ny, &s);
  const int n = s.plate.n;
  const long steps = std::max(20L, std::min(1000L, static_cast<long>(3e6 / n)));
  const double h = 0.9 * h_cd * (1.0 / ny) / dx_ref;
  // The four solvers in turn, kScaleRounds times, each one's median over the rounds: a burst of
  // load on this shared machine then falls on one round of every solver, not on one solver.
  std::vector<double> per_step[4];
  for (int r = 0; r < kScaleRounds; ++r) {
    per_step[0].push_back(
        PerStep([h](Scene* sc, wp::Outcome* o) { return HandRun(sc, h, o); }, &s, h, steps));
    for (int k = 0; k < 3; ++k) {
      const double hk = kScaleFrac[k] * h;
      const char* m = kScaleSets[k];
      per_step[k + 1].push_back(
          PerStep([&](Scene* sc, wp::Outcome* o) { return wp::CeodeRun(ctx, sc->p, m, hk, o); },
                  &s, hk, steps));
    }
  }
  ScalePoint p{n, 0, 0, 0, 0};
  double* out[4] = {&p.hand, &p.cd, &p.a34, &p.o4};
  for (int k = 0; k < 4; ++k) *out[k] = wp::MedianOf(per_step[k]);
  return p;
}

std::string ScalingCsvPath(const std::string& csv) {
  if (csv.empty()) return "";
  const size_t dot = csv.rfind(".csv");
  return (dot == std::string::npos ? csv : csv.substr(0, dot)) + "_scaling.csv";
}

int ScalingPart(SUNContext ctx, const wp::Args& args, double h_cd, double dx_ref) {
  const std::vector<int> nys =
      args.quick ? std::vector<int>{12, 24} : std::vector<int>{35, 112, 354};
  std::printf(
      "\n== scaling: 4 ny x ny meshes, seconds per step = (T(2S) - T(S)) / S, median of 3 "
      "interleaved rounds ==\n");
  std::printf("%9s %12s %12s %12s %12s %9s %9s %9s\n", "DOF", "hand ns/dof", "G3_CD", "G4_A34",
              "G5_O4", "CD/hand", "A34/hand", "O4/hand");
  const std::string path = ScalingCsvPath(args.csv);
  FILE* f = path.empty() ? nullptr : std::fopen(path.c_str(), "w");
  if (f != nullptr) std::fputs("dof,hand_s_per_step,g3_cd,g4_a34,g5_o4\n", f);
  std::vector<ScalePoint> pts;
  int bad = 0;
  for (int ny : nys) {
    const ScalePoint p = ScaleAt(ctx, ny, h_cd, dx_ref);
    pts.push_back(p);
    if (std::isnan(p.hand) || std::isnan(p.cd) || std::isnan(p.a34) || std::isnan(p.o4)) ++bad;
    if (std::min({p.hand, p.cd, p.a34, p.o4}) <= 0) {
      std::printf("(timing noise at %d DOF: a per-step difference came out <= 0)\n", p.n);
    }
    const double dof = p.n;
    std::printf("%9d %12.3f %12.3f %12.3f %12.3f %9.3f %9.3f %9.3f\n", p.n, 1e9 * p.hand / dof,
                1e9 * p.cd / dof, 1e9 * p.a34 / dof, 1e9 * p.o4 / dof, p.cd / p.hand,
                p.a34 / p.hand, p.o4 / p.hand);
    if (f != nullptr) std::fprintf(f, "%d,%.6e,%.6e,%.6e,%.6e\n", p.n, p.hand, p.cd, p.a34, p.o4);
  }
  if (f != nullptr) std::fclose(f);
  if (pts.size() >= 2) {
    const ScalePoint& a = pts.front();
    const ScalePoint& b = pts.back();
    const double lr = std::log(static_cast<double>(b.n) / a.n);
    std::printf(
        "log-log slope of time per step against N (%d to %d): hand %.3f, G3_CD %.3f, "
        "G4_A34 %.3f, G5_O4 %.3f\n",
        a.n, b.n, std::log(b.hand / a.hand) / lr, std::log(b.cd / a.cd) / lr,
        std::log(b.a34 / a.a34) / lr, std::log(b.o4 / a.o4) / lr);
  }
  return bad;
}

// ------------------------------------------------------- instruction counts
// wp_fe_plate --count SOLVER NY STEPS: SOLVER (hand, G3_CD, G4_A34 or G5_O4) integrates the scaling
// scene on the 4 NY x NY mesh for STEPS steps, untimed, and prints its step count. Under callgrind
// (bench/step_cost/instructions.sh fe-plate) two step counts give instructions and simulated cache misses per
// step, counts that do not move with the machine's load. The step is 0.9 x 2 / (largest element
// frequency), inside G3_CD's limit since that bound is above omega_max (part 1).
int CountMain(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr, "usage: %s --count hand|G3_CD|G4_A34|G5_O4 NY STEPS\n", argv[0]);
    return 2;
  }
  const std::string solver = argv[2];
  const int ny = std::atoi(argv[3]);
  const long steps = std::atol(argv[4]);
  const double* frac = nullptr;
  for (int k = 0; k < 3; ++k) {
    if (solver == kScaleSets[k]) frac = &kScaleFrac[k];
  }
  if (ny < 1 || steps < 1 || (frac == nullptr && solver != "hand")) {
    std::fprintf(stderr, "--count: unknown solver '%s' or NY, STEPS below 1\n", solver.c_str());
    return 2;
  }
  SUNContext ctx = nullptr;
  if (wp::Failed(SUNContext_Create(SUN_COMM_NULL, &ctx), "SUNContext_Create")) return 1;
  Scene s;
  MakeScaleScene(ny, &s);
  const double h = 0.9 * 2 / ElementBound(s.plate) * (frac == nullptr ? 1.0 : *frac);
  s.p.tend = h * static_cast<double>(steps);
  wp::Outcome o;
  const int rc = frac == nullptr ? HandRun(&s, h, &o) : wp::CeodeRun(ctx, s.p, solver.c_str(), h, &o);
  std::printf("%s on %d DOF: %ld steps (asked %ld), run %s\n", solver.c_str(), s.plate.n, o.steps,
              steps, rc == 0 ? "ok" : "FAILED");
  SUNContext_Free(&ctx);
  return rc == 0 && o.steps == steps ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc > 1 && std::string(argv[1]) == "--count") return CountMain(argc, argv);
  const wp::Args args = wp::ParseArgs(argc, argv);
  SUNContext ctx = nullptr;
  if (wp::Failed(SUNContext_Create(SUN_COMM_NULL, &ctx), "SUNContext_Create")) return 1;
  Scene s;
  // Square elements, L/D = 4 (quick: a coarser mesh of the same plate).
  s.plate = args.quick ? fe::MakePlate(16, 4) : fe::MakePlate(48, 12);
  const double res = LowestModes(&s);
  FillProblem(&s);
  std::printf(
      "Q4 cantilever 4 x 1, plane stress, E = 1, nu = 0.3, rho = 1; reference: two lowest "
      "modes (residual %.2e)\n",
      res);
  int bad = res < 1e-9 ? 0 : 1;
  bad += StableStepPart(ctx, args.quick, &s);
  const WpResult wr = WorkPrecisionPart(ctx, &s, args);
  bad += wr.bad;
  bad += ScalingPart(ctx, args, wr.h_cd, s.plate.Lx / s.plate.nx);
  std::printf("%d problem(s)\n", bad);
  SUNContext_Free(&ctx);
  return bad == 0 ? 0 : 1;
}
