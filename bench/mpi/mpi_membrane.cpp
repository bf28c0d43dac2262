// CEODE on NVECTOR_PARALLEL (docs/mpi.md): a partitioned model with a halo exchange
// inside f, against the same problem on one NVECTOR_SERIAL vector. Two models, one driver:
//   mpi_membrane  the membrane of bench/mpi_membrane_model.h (5-point Laplacian, lumped unit
//                 masses, fixed edges; N = nx * ny DOF), one strip of grid rows per rank;
//   mpi_fe_plate  the Q4 cantilever plate of wp_fe_plate (bench/mpi_fe_plate_model.h: K in CSR,
//                 lumped M, a 4 ny x ny mesh of about N DOF), one block of node columns per rank.
//
// In one run (mpiexec -n 2), side by side and interleaved repetition by repetition:
//   serial  NVECTOR_SERIAL, the whole grid on rank 0 (CEODE's fused serial kernel);
//   1 rank  NVECTOR_PARALLEL on MPI_COMM_SELF, the whole grid on rank 0 (the fused kernel too);
//   P ranks NVECTOR_PARALLEL on MPI_COMM_WORLD, one strip per rank;
//   petsc   NVECTOR_PETSC on 1 rank and on P (built with CEODE_HAVE_PETSC, i.e. against Debian's
//           SUNDIALS): the same strips on PETSc MPI Vecs, which expose no array to CEODE, so
//           its generic N_Vector path; f reaches the entries through VecGetArray;
// while one configuration runs, the ranks it does not use sleep (no busy polling), so a
// 1-rank timing is not slowed by an idle rank spinning on the second core.
// Time per step is the fastest repetition's (the slowest rank's) wall time over the timed
// steps; the speedup is 1-rank time over P-rank time. The guard's start-up check and the first
// steps are outside the timed interval.
//
// Checks (exit code 1 when one fails; never on a timing): the gathered P-rank states and the
// 1-rank states (NVECTOR_PARALLEL and NVECTOR_PETSC) are bitwise equal to the serial state; the
// hand loop agrees with CEODE to 1e-12; the model's own accuracy check (model::Accuracy): on the
// membrane, for G3_CD, the exact solution of the central-difference recurrence on the two excited
// modes (x_n = cos(n theta) x_0 with cos(theta) = 1 - (omega h)^2 / 2) to 1e-9 relative, other sets
// the exact ODE solution to 1e-3; on the plate, a bounded state (its accuracy is wp_fe_plate's
// check).
//
//   mpiexec -n 2 mpi_membrane|mpi_fe_plate [--n N] [--steps S] [--reps R] [--method NAME]
//                                      [--csv FILE]
//   mpiexec -n 2 mpi_membrane --quick        (N = 10^4, 100 steps, 1 repetition: ctest)
//   ... --no-halo    (negative control: the P-rank run skips its halo exchanges; exit 1)
// Defaults: N = 10^6 (1000 x 1000), 300 steps, 3 repetitions, G3_CD at 0.9 of its limit.
#include <ceode/ceode.h>
#include <ceode/ceode_stability.h>
#include <time.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "ceode_sundials_compat.h"
#if defined(CEODE_HAVE_PETSC)
#include <nvector/nvector_petsc.h>
#include <petscvec.h>
#endif
// One driver, two partitioned models with the same interface (CMake builds both):
#if defined(CEODE_MPI_FE_PLATE)
#include "mpi_fe_plate_model.h"
namespace model = fe_strip;  // mpi_fe_plate: the Q4 plate, one block of node columns per rank
#else
#include "mpi_membrane_model.h"
namespace model = membrane;  // mpi_membrane: the 5-point membrane, one row strip per rank
#endif

// CEODE's global reductions (every norm or dot product on NVECTOR_PARALLEL is an MPI_Allreduce),
// counted through MPI's profiling interface so that the report can state them per step. A global
// because that interface passes no user pointer.
long g_allreduce_calls = 0;  // NOLINT(cppcoreguidelines-avoid-non-const-global-variables)

// The name in parentheses: PETSc's logging defines MPI_Allreduce as a function-like macro.
extern "C" int(MPI_Allreduce)(const void* sendbuf, void* recvbuf, int count, MPI_Datatype type,
                              MPI_Op op, MPI_Comm comm) {
  ++g_allreduce_calls;
  return PMPI_Allreduce(sendbuf, recvbuf, count, type, op, comm);
}

namespace {

struct Options {
  long n = 1000000;
  long steps = 300;
  int reps = 3;
  std::string method = "G3_CD";
  std::string csv;
  double h_factor = 0.9;
  bool quick = false;
  bool no_halo = false;  // negative control: the P-rank f never exchanges (the checks must fail)
};

bool ParseArgs(int argc, char** argv, Options* o) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool more = i + 1 < argc;
    if (a == "--quick") {
      o->quick = true;
      o->n = 10000;
      o->steps = 100;
      o->reps = 1;
    } else if (a == "--n" && more) {
      o->n = std::atol(argv[++i]);
    } else if (a == "--steps" && more) {
      o->steps = std::atol(argv[++i]);
    } else if (a == "--reps" && more) {
      o->reps = std::atoi(argv[++i]);
    } else if (a == "--method" && more) {
      o->method = argv[++i];
    } else if (a == "--no-halo") {
      o->no_halo = true;
    } else if (a == "--csv" && more) {
      o->csv = argv[++i];
    } else {
      return false;
    }
  }
  return o->n >= 4 && o->steps >= 4 && o->reps >= 1;
}

// All ranks of comm meet here without spinning: a rank that waits for a long computation on
// another rank sleeps 0.2 ms between tests instead of busy-polling a core.
void SleepyBarrier(MPI_Comm comm) {
  MPI_Request req;
  MPI_Ibarrier(comm, &req);
  int done = 0;
  const timespec pause{0, 200000};
  for (MPI_Test(&req, &done, MPI_STATUS_IGNORE); !done; MPI_Test(&req, &done, MPI_STATUS_IGNORE)) {
    nanosleep(&pause, nullptr);
  }
}

struct Timing {
  int flag = CE_SUCCESS;
  double seconds = 0;  // the slowest rank's wall time over the timed steps
  double cpu = 0;      // the slowest rank's CPU time (less sensitive to a loaded machine)
  long timed_steps = 0;
  long allreduces = 0;        // MPI_Allreduce calls in the timed steps (this rank)
  long exchanges = 0;         // halo exchanges in the timed steps (this rank)
  long start_allreduces = 0;  // ... in CEODE's start, the guard's check and the first steps
  long start_exchanges = 0;
};

double CpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

constexpr long kWarmSteps = 2;  // the start (and the guard's check) happen here, untimed

// The local entries of x: its array, or a PETSc Vec's, checked out until ReleaseArray.
double* AcquireArray(N_Vector x) {
#if defined(CEODE_HAVE_PETSC)
  if (N_VGetVectorID(x) == SUNDIALS_NVEC_PETSC) {
    PetscScalar* a = nullptr;
    return VecGetArray(N_VGetVector_Petsc(x), &a) == 0 ? a : nullptr;
  }
#endif
  return N_VGetArrayPointer(x);
}

void ReleaseArray(N_Vector x, double* a) {
#if defined(CEODE_HAVE_PETSC)
  if (N_VGetVectorID(x) == SUNDIALS_NVEC_PETSC) VecRestoreArray(N_VGetVector_Petsc(x), &a);
#else
  (void)x;
  (void)a;
#endif
}

// f on any of the vector kinds: the model's Accel (with its halo exchange) on the local arrays.
int AnyRhs(sunrealtype t, N_Vector x, N_Vector v, N_Vector f, void* data) {
  if (N_VGetVectorID(x) != SUNDIALS_NVEC_PETSC) return model::Rhs(t, x, v, f, data);
  double* xa = AcquireArray(x);
  double* fa = AcquireArray(f);
  const int rv =
      xa != nullptr && fa != nullptr ? model::Accel(static_cast<model::Strip*>(data), xa, fa) : -1;
  ReleaseArray(x, xa);
  ReleaseArray(f, fa);
  return rv;
}

// A CEODE memory for the model on x, v (any of the vector kinds), at the initial state.
void* CreateSolver(N_Vector x, N_Vector v, model::Strip* s, const Options& o, double h) {
  double* xa = AcquireArray(x);
  double* va = AcquireArray(v);
  model::InitialState(*s, xa, va);
  ReleaseArray(x, xa);
  ReleaseArray(v, va);
  void* mem = CEodeCreate(x->sunctx);
  int flag = mem == nullptr ? CE_MEM_FAIL : CEodeInit(mem, AnyRhs, 0, x, v);
  if (flag == CE_SUCCESS) flag = CEodeSetMethodByName(mem, o.method.c_str());
  if (flag == CE_SUCCESS) flag = CEodeSetFixedStep(mem, h);
  if (flag == CE_SUCCESS) flag = CEodeSetUserData(mem, s);
  if (flag == CE_SUCCESS) flag = CEodeSetMaxNumSteps(mem, o.steps + 10);
  if (flag != CE_SUCCESS) CEodeFree(&mem);
  return mem;
}

// Integrates the membrane to steps * h; the state ends in x.
Timing Integrate(N_Vector x, N_Vector v, model::Strip* s, const Options& o, double h,
                 MPI_Comm timing_comm) {
  Timing tm;
  const long red_start = g_allreduce_calls;
  const long exch_start = s->nexchange;
  void* mem = CreateSolver(x, v, s, o, h);
  int flag = mem == nullptr ? CE_ILL_INPUT : CE_SUCCESS;
  sunrealtype t = 0;
  if (flag == CE_SUCCESS) flag = CEodeEvolve(mem, kWarmSteps * h, x, v, &t, CE_NORMAL);
  const long red0 = g_allreduce_calls;
  const long exch0 = s->nexchange;
  tm.start_allreduces = red0 - red_start;
  tm.start_exchanges = exch0 - exch_start;
  MPI_Barrier(timing_comm);
  const double t0 = MPI_Wtime();
  const double c0 = CpuSeconds();
  if (flag == CE_SUCCESS) {
    flag = CEodeEvolve(mem, static_cast<double>(o.steps) * h, x, v, &t, CE_NORMAL);
  }
  double dt[2] = {MPI_Wtime() - t0, CpuSeconds() - c0};
  tm.allreduces = g_allreduce_calls - red0;
  tm.exchanges = s->nexchange - exch0;
  MPI_Allreduce(MPI_IN_PLACE, dt, 2, MPI_DOUBLE, MPI_MAX, timing_comm);
  MPI_Allreduce(MPI_IN_PLACE, &flag, 1, MPI_INT, MPI_MIN, timing_comm);
  tm.flag = flag;
  tm.seconds = dt[0];
  tm.cpu = dt[1];
  tm.timed_steps = o.steps - kWarmSteps;
  CEodeFree(&mem);
  return tm;
}

// The practical limit on the same partition, for the scaling: a hand-written central-differences
// loop (velocity form, G3_CD's arithmetic up to the order of its sums) on the strip's own arrays:
// f as its own pass (the same halo-exchanging Accel), then one update pass, x and v in place, no
// norm, no check. The state at steps * h ends in *x (this strip's entries).
Timing HandIntegrate(model::Strip* s, const Options& o, double h, MPI_Comm timing_comm,
                     std::vector<double>* x) {
  Timing tm;
  const long n = model::LocalLength(*s);
  x->assign(static_cast<size_t>(n), 0.0);
  std::vector<double> v(x->size()), a(x->size()), an(x->size());
  double* xp = x->data();
  model::InitialState(*s, xp, v.data());
  int rv = model::Accel(s, xp, a.data());
  const double hb = 0.5 * h;
  const double h2 = 0.5 * h * h;
  for (long i = 0; i < n; ++i) xp[i] += h * v[i] + h2 * a[i];  // x(h)
  const auto step = [&] {  // at t: a(t) = f(x(t)), v(t), x(t + h)
    rv |= model::Accel(s, xp, an.data());
    for (long i = 0; i < n; ++i) {
      v[i] += hb * (a[i] + an[i]);
      xp[i] += h * v[i] + h2 * an[i];
    }
    a.swap(an);
  };
  for (long k = 1; k < kWarmSteps; ++k) step();
  MPI_Barrier(timing_comm);
  const double t0 = MPI_Wtime();
  const double c0 = CpuSeconds();
  for (long k = kWarmSteps; k < o.steps; ++k) step();
  double dt[2] = {MPI_Wtime() - t0, CpuSeconds() - c0};
  MPI_Allreduce(MPI_IN_PLACE, dt, 2, MPI_DOUBLE, MPI_MAX, timing_comm);
  MPI_Allreduce(MPI_IN_PLACE, &rv, 1, MPI_INT, MPI_BOR, timing_comm);
  tm.flag = rv == 0 ? CE_SUCCESS : CE_RHSFUNC_FAIL;
  tm.seconds = dt[0];
  tm.cpu = dt[1];
  tm.timed_steps = o.steps - kWarmSteps;
  return tm;
}

// The step: h_factor times the set's stability limit Omega_max / omega_max (exact omega_max).
double StepSize(const Options& o, const model::Strip& s) {
  int degree = 0;
  sunrealtype params[16];
  sunrealtype Omega = 0;
  if (CEodeGetMethodParams(o.method.c_str(), &degree, params, 16) != CE_SUCCESS ||
      CEodeStabilityLimit(degree, params, 0, &Omega) != CE_SUCCESS || Omega <= 0) {
    return -1;
  }
  return o.h_factor * Omega / model::OmegaMax(s);
}

struct Compare {
  long ndiff = 0;
  double maxdiff = 0;
};

uint64_t Bits(double d) {
  uint64_t u = 0;
  std::memcpy(&u, &d, sizeof u);
  return u;
}

// Bitwise comparison (so -0 and +0 differ, a NaN never matches), and the largest |a - b|.
Compare Diff(const double* a, const double* b, long n) {
  Compare c;
  for (long i = 0; i < n; ++i) {
    if (Bits(a[i]) != Bits(b[i])) ++c.ndiff;
    const double d = std::fabs(a[i] - b[i]);
    if (!(d <= c.maxdiff)) c.maxdiff = d;
  }
  return c;
}

// One configuration's repetitions (seconds per step) and its last run's flag.
struct Config {
  std::string name;
  int ranks = 1;
  std::vector<double> per_step;      // wall time
  std::vector<double> cpu_per_step;  // CPU time
  int flag = CE_SUCCESS;
  double allreduces_per_step = 0;  // rank 0's, last repetition
  double exchanges_per_step = 0;
  long start_allreduces = 0;
  long start_exchanges = 0;
  double Best() const { return *std::min_element(per_step.begin(), per_step.end()); }
  double BestCpu() const { return *std::min_element(cpu_per_step.begin(), cpu_per_step.end()); }
};

void Record(Config* c, const Timing& tm) {
  c->flag = tm.flag != CE_SUCCESS ? tm.flag : c->flag;
  const auto steps = static_cast<double>(tm.timed_steps);
  c->per_step.push_back(tm.seconds / steps);
  c->cpu_per_step.push_back(tm.cpu / steps);
  c->allreduces_per_step = static_cast<double>(tm.allreduces) / steps;
  c->exchanges_per_step = static_cast<double>(tm.exchanges) / steps;
  c->start_allreduces = tm.start_allreduces;
  c->start_exchanges = tm.start_exchanges;
}

std::string LoadAverage() {
  std::string text = "?";
  if (FILE* f = std::fopen("/proc/loadavg", "r")) {
    char buf[128] = {0};
    if (std::fgets(buf, sizeof buf, f) != nullptr) text = std::string(buf, std::strcspn(buf, "\n"));
    std::fclose(f);
  }
  return text;
}

// Everything one rank owns: the strips and vectors of the three configurations.
struct Problem {
  model::Strip whole;  // the serial and the 1-rank runs (rank 0)
  model::Strip self;
  model::Strip world;  // one strip per rank
  SUNContext ctx_serial = nullptr;
  SUNContext ctx_self = nullptr;
  SUNContext ctx_world = nullptr;
  N_Vector xs = nullptr, vs = nullptr, x1 = nullptr, v1 = nullptr, xp = nullptr, vp = nullptr;
  N_Vector xq1 = nullptr, vq1 = nullptr, xqp = nullptr, vqp = nullptr;  // NVECTOR_PETSC
  std::vector<double> hand1;  // the hand loop's state on 1 rank (rank 0) and on this rank's strip
  std::vector<double> handp;
};

// An NVECTOR_PETSC vector on a new PETSc MPI Vec of local length len (its x owns no Vec: Teardown
// destroys it), or nullptr without PETSc.
N_Vector NewPetscVector(MPI_Comm comm, long len, long n, SUNContext ctx) {
#if defined(CEODE_HAVE_PETSC)
  Vec X = nullptr;
  if (VecCreateMPI(comm, len, n, &X) != 0) MPI_Abort(MPI_COMM_WORLD, 1);
  return N_VMake_Petsc(X, ctx);
#else
  (void)comm, (void)len, (void)n, (void)ctx;
  return nullptr;
#endif
}

void DestroyPetscVector(N_Vector* x) {
#if defined(CEODE_HAVE_PETSC)
  if (*x == nullptr) return;
  Vec X = N_VGetVector_Petsc(*x);
  N_VDestroy(*x);
  VecDestroy(&X);
  *x = nullptr;
#else
  (void)x;
#endif
}

N_Vector CloneOrNull(N_Vector x) { return x != nullptr ? N_VClone(x) : nullptr; }

void Setup(Problem* p, long n_target, int rank, int size) {
  MPI_Comm world = MPI_COMM_WORLD;
  MPI_Comm self = MPI_COMM_SELF;
  p->whole = model::MakeStrip(MPI_COMM_NULL, n_target);
  p->self = model::MakeStrip(self, n_target);
  p->world = model::MakeStrip(world, n_target);
  const long n = model::GlobalLength(p->whole);
  if (SUNContext_Create(CEODE_SUN_COMM_ARG(world), &p->ctx_world) != 0) MPI_Abort(world, 1);
  if (size > 1) {
    p->xp = N_VNew_Parallel(world, model::LocalLength(p->world), n, p->ctx_world);
    p->vp = N_VClone(p->xp);
    p->xqp = NewPetscVector(world, model::LocalLength(p->world), n, p->ctx_world);
    p->vqp = CloneOrNull(p->xqp);
  }
  if (rank != 0) return;
  if (SUNContext_Create(SUN_COMM_NULL, &p->ctx_serial) != 0) MPI_Abort(world, 1);
  if (SUNContext_Create(CEODE_SUN_COMM_ARG(self), &p->ctx_self) != 0) MPI_Abort(world, 1);
  p->xs = N_VNew_Serial(n, p->ctx_serial);
  p->vs = N_VClone(p->xs);
  p->x1 = N_VNew_Parallel(self, n, n, p->ctx_self);
  p->v1 = N_VClone(p->x1);
  p->xq1 = NewPetscVector(self, n, n, p->ctx_self);
  p->vq1 = CloneOrNull(p->xq1);
}

void Teardown(Problem* p) {
  for (N_Vector* v : {&p->vq1, &p->vqp}) {  // N_VClone's Vecs belong to their N_Vector
    if (*v != nullptr) N_VDestroy(*v);
  }
  DestroyPetscVector(&p->xq1);
  DestroyPetscVector(&p->xqp);
  for (N_Vector* v : {&p->xs, &p->vs, &p->x1, &p->v1, &p->xp, &p->vp}) {
    if (*v != nullptr) N_VDestroy(*v);
  }
  for (SUNContext* c : {&p->ctx_serial, &p->ctx_self, &p->ctx_world}) {
    if (*c != nullptr) SUNContext_Free(c);
  }
}

// The repetitions, interleaved so that a change of machine load hits every configuration.
// cfg: serial, parallel 1 rank, parallel P ranks, hand 1 rank, hand P ranks (the same partition
// without CEODE, G3_CD only), PETSc 1 rank, PETSc P ranks (with CEODE_HAVE_PETSC); P-rank entries
// only when size > 1.
enum { kSerial, kOne, kMany, kHandOne, kHandMany, kPetscOne, kPetscMany, kNumConfigs };

std::vector<Config> Measure(Problem* p, const Options& o, double h, int rank, int size) {
  std::vector<Config> cfg(kNumConfigs);
  const char* names[kNumConfigs] = {"serial", "parallel", "parallel", "hand",
                                    "hand",   "petsc",    "petsc"};
  for (int c = 0; c < kNumConfigs; ++c) {
    cfg[c].name = names[c];
    cfg[c].ranks = c == kMany || c == kHandMany || c == kPetscMany ? size : 1;
  }
  const bool hand = o.method == "G3_CD";
  for (int r = 0; r < o.reps; ++r) {
    if (rank == 0) {
      Record(&cfg[kSerial], Integrate(p->xs, p->vs, &p->whole, o, h, MPI_COMM_SELF));
    }
    SleepyBarrier(MPI_COMM_WORLD);
    if (rank == 0) {
      Record(&cfg[kOne], Integrate(p->x1, p->v1, &p->self, o, h, MPI_COMM_SELF));
    }
    SleepyBarrier(MPI_COMM_WORLD);
    if (size > 1) {
      Record(&cfg[kMany], Integrate(p->xp, p->vp, &p->world, o, h, MPI_COMM_WORLD));
    }
    SleepyBarrier(MPI_COMM_WORLD);
    if (rank == 0 && p->xq1 != nullptr) {
      Record(&cfg[kPetscOne], Integrate(p->xq1, p->vq1, &p->self, o, h, MPI_COMM_SELF));
    }
    SleepyBarrier(MPI_COMM_WORLD);
    if (size > 1 && p->xqp != nullptr) {
      Record(&cfg[kPetscMany], Integrate(p->xqp, p->vqp, &p->world, o, h, MPI_COMM_WORLD));
    }
    if (rank == 0 && hand) {
      Record(&cfg[kHandOne], HandIntegrate(&p->self, o, h, MPI_COMM_SELF, &p->hand1));
    }
    SleepyBarrier(MPI_COMM_WORLD);
    if (size > 1 && hand) {
      Record(&cfg[kHandMany], HandIntegrate(&p->world, o, h, MPI_COMM_WORLD, &p->handp));
    }
  }
  return cfg;
}

// A P-rank state (this rank's strip at local) on rank 0, in global order (the strips are
// contiguous blocks).
std::vector<double> Gather(const Problem& p, const double* local, int rank, int size) {
  std::vector<double> all;
  if (size == 1 || local == nullptr) return all;
  std::vector<int> counts(static_cast<size_t>(size)), displs(static_cast<size_t>(size));
  for (int r = 0; r < size; ++r) {
    long off = 0, len = 0;
    model::Range(p.world, r, &off, &len);
    counts[r] = static_cast<int>(len);
    displs[r] = static_cast<int>(off);
  }
  if (rank == 0) all.resize(static_cast<size_t>(model::GlobalLength(p.world)));
  MPI_Gatherv(local, static_cast<int>(model::LocalLength(p.world)), MPI_DOUBLE, all.data(),
              counts.data(), displs.data(), MPI_DOUBLE, 0, MPI_COMM_WORLD);
  return all;
}

}  // namespace

namespace {

struct Verdict {
  bool ok = true;
  Compare one;         // 1 rank against serial
  Compare many;        // P ranks against serial
  Compare hand;        // the hand loop on 1 rank against CEODE serial (rounding apart)
  Compare hand_many;   // the hand loop on P ranks against on 1 rank (bitwise)
  Compare petsc_one;   // NVECTOR_PETSC on 1 rank against serial
  Compare petsc_many;  // ... on P ranks
  bool petsc = false;
  double error = 0;
  double tol = 0;
  const char* what = "";
  bool discrete = false;
};

// The hand loop sums in its own order: it must agree with CEODE to rounding, and on P ranks
// bitwise with itself on one.
constexpr double kHandTol = 1e-12;

// Rank 0: bitwise equality of the parallel states with the serial one, and the accuracy check.
Verdict Check(const Problem& p, const std::vector<double>& gathered,
              const std::vector<double>& hand_gathered, const std::vector<double>& petsc_gathered,
              const Options& o, double h, const std::vector<Config>& cfg) {
  Verdict v;
  const long n = model::GlobalLength(p.whole);
  const double* xs = N_VGetArrayPointer(p.xs);
  v.one = Diff(xs, N_VGetArrayPointer(p.x1), n);
  if (!gathered.empty()) v.many = Diff(xs, gathered.data(), n);
  v.petsc = p.xq1 != nullptr;
  if (v.petsc) {
    double* q = AcquireArray(p.xq1);
    v.petsc_one = Diff(xs, q, n);
    ReleaseArray(p.xq1, q);
  }
  if (!petsc_gathered.empty()) v.petsc_many = Diff(xs, petsc_gathered.data(), n);
  if (!p.hand1.empty()) {
    v.hand = Diff(xs, p.hand1.data(), n);
    v.ok = v.hand.maxdiff <= kHandTol;
  }
  if (!hand_gathered.empty()) {
    v.hand_many = Diff(p.hand1.data(), hand_gathered.data(), n);
    v.ok = v.ok && v.hand_many.ndiff == 0;
  }
  v.discrete = o.method == "G3_CD";
  v.error = model::Accuracy(p.whole, xs, o.steps, h, v.discrete, &v.tol, &v.what);
  const double tol = v.tol;
  for (const Config& c : cfg) v.ok = v.ok && c.flag == CE_SUCCESS;
  v.ok = v.ok && v.one.ndiff == 0 && v.many.ndiff == 0 && v.petsc_one.ndiff == 0 &&
         v.petsc_many.ndiff == 0 && v.error <= tol;
  return v;
}

void Table(const std::vector<Config>& cfg, long n, int size) {
  std::printf("%-10s %5s %10s %14s %12s  %s\n", "vector", "ranks", "ms/step", "ns/(DOF step)",
              "CPU ms/step", "repetitions (wall ms/step)");
  for (const Config& c : cfg) {
    if (c.per_step.empty()) continue;
    std::string reps;
    for (double s : c.per_step) reps += " " + std::to_string(s * 1e3).substr(0, 7);
    std::printf("%-10s %5d %10.4f %14.3f %12.4f %s\n", c.name.c_str(), c.ranks, c.Best() * 1e3,
                c.Best() * 1e9 / static_cast<double>(n), c.BestCpu() * 1e3, reps.c_str());
  }
  if (size == 1) return;
  std::printf(
      "communication per step on %d ranks: %.3g MPI_Allreduce (CEODE's norms), %.3g "
      "halo exchanges (f); before the timed steps (CEODE's start, the guard's check, %ld "
      "steps): %ld MPI_Allreduce, %ld halo exchanges\n",
      size, cfg[kMany].allreduces_per_step, cfg[kMany].exchanges_per_step, kWarmSteps,
      cfg[kMany].start_allreduces, cfg[kMany].start_exchanges);
  std::printf(
      "speedup 1 -> %d ranks (NVECTOR_PARALLEL): %.3f wall, %.3f CPU time of the slowest "
      "rank (target >= 1.6 wall at N = 10^6 on 2 ranks; a timing, not a check)\n",
      size, cfg[kOne].Best() / cfg[kMany].Best(), cfg[kOne].BestCpu() / cfg[kMany].BestCpu());
  if (!cfg[kPetscOne].per_step.empty() && !cfg[kPetscMany].per_step.empty()) {
    std::printf(
        "speedup 1 -> %d ranks (NVECTOR_PETSC, CEODE's generic path): %.3f wall, %.3f CPU; "
        "PETSc / NVECTOR_PARALLEL per step: %.3f on 1 rank, %.3f on %d\n",
        size, cfg[kPetscOne].Best() / cfg[kPetscMany].Best(),
        cfg[kPetscOne].BestCpu() / cfg[kPetscMany].BestCpu(),
        cfg[kPetscOne].Best() / cfg[kOne].Best(), cfg[kPetscMany].Best() / cfg[kMany].Best(), size);
  }
  if (cfg[kHandOne].per_step.empty() || cfg[kHandMany].per_step.empty()) return;
  std::printf(
      "speedup 1 -> %d ranks of the hand loop (the machine's limit for this f and update): "
      "%.3f wall, %.3f CPU; CEODE / hand per step: %.3f on 1 rank, %.3f on %d\n",
      size, cfg[kHandOne].Best() / cfg[kHandMany].Best(),
      cfg[kHandOne].BestCpu() / cfg[kHandMany].BestCpu(), cfg[kOne].Best() / cfg[kHandOne].Best(),
      cfg[kMany].Best() / cfg[kHandMany].Best(), size);
}

void Report(const Options& o, const Problem& p, double h, const std::vector<Config>& cfg,
            const Verdict& v, const std::string& load0, int size) {
  const long n = model::GlobalLength(p.whole);
  std::printf(
      "%s on NVECTOR_PARALLEL: N = %ld, %s at h = %.6g (%.2f of the limit), %ld timed steps, "
      "best of %d; %d MPI ranks\n",
      model::Describe(p.whole).c_str(), n, o.method.c_str(), h, o.h_factor, o.steps - kWarmSteps,
      o.reps, size);
  Table(cfg, n, size);
  std::printf("bitwise: 1 rank vs serial: %ld of %ld entries differ (max |diff| %.3g)", v.one.ndiff,
              n, v.one.maxdiff);
  if (size > 1) {
    std::printf("; %d ranks vs serial: %ld differ (max |diff| %.3g)", size, v.many.ndiff,
                v.many.maxdiff);
  }
  if (v.petsc) {
    std::printf("\nbitwise, NVECTOR_PETSC: 1 rank vs serial: %ld differ (max |diff| %.3g)",
                v.petsc_one.ndiff, v.petsc_one.maxdiff);
    if (size > 1) {
      std::printf("; %d ranks vs serial: %ld differ (max |diff| %.3g)", size, v.petsc_many.ndiff,
                  v.petsc_many.maxdiff);
    }
  }
  if (!p.hand1.empty()) {
    std::printf("\nhand loop: 1 rank vs CEODE serial max |diff| %.3g (tolerance %g)",
                v.hand.maxdiff, kHandTol);
    if (size > 1) {
      std::printf("; %d ranks vs 1 rank: %ld of %ld entries differ", size, v.hand_many.ndiff, n);
    }
  }
  std::printf("\naccuracy: %s = %.3e (tolerance %g)\n", v.what, v.error, v.tol);
  std::printf("load average (1/5/15 min, running/total): %s at the start, %s at the end\n",
              load0.c_str(), LoadAverage().c_str());
  std::printf("checks: %s\n", v.ok ? "passed" : "FAILED");
}

void WriteCsv(const Options& o, const Problem& p, double h, const std::vector<Config>& cfg) {
  FILE* f = std::fopen(o.csv.c_str(), "w");
  if (f == nullptr) return;
  std::fprintf(
      f, "vector,ranks,n,nx,ny,method,h,timed_steps,rep,seconds_per_step,cpu_seconds_per_step\n");
  for (const Config& c : cfg) {
    for (size_t r = 0; r < c.per_step.size(); ++r) {
      std::fprintf(f, "%s,%d,%ld,%d,%d,%s,%.9g,%ld,%zu,%.6e,%.6e\n", c.name.c_str(), c.ranks,
                   model::GlobalLength(p.whole), p.whole.nx, p.whole.ny, o.method.c_str(), h,
                   o.steps - kWarmSteps, r, c.per_step[r], c.cpu_per_step[r]);
    }
  }
  std::fclose(f);
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
#if defined(CEODE_HAVE_PETSC)
  // On the MPI already initialised: PetscFinalize leaves MPI to MPI_Finalize.
  if (PetscInitializeNoArguments() != 0) MPI_Abort(MPI_COMM_WORLD, 1);
#endif
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  Options o;
  if (!ParseArgs(argc, argv, &o)) {
    if (rank == 0) {
      std::fprintf(stderr,
                   "usage: mpiexec -n P mpi_membrane [--quick] [--n N] [--steps S] "
                   "[--reps R] [--method NAME] [--csv FILE] [--no-halo]\n");
    }
    MPI_Finalize();
    return 2;
  }
  const std::string load0 = LoadAverage();
  Problem p;
  Setup(&p, o.n, rank, size);
  p.world.exchange = !o.no_halo;
  const double h = StepSize(o, p.whole);
  int bad = h > 0 ? 0 : 1;
  if (bad == 0) {
    const std::vector<Config> cfg = Measure(&p, o, h, rank, size);
    const std::vector<double> gathered =
        Gather(p, p.xp != nullptr ? N_VGetArrayPointer(p.xp) : nullptr, rank, size);
    const std::vector<double> hand_gathered =
        Gather(p, p.handp.empty() ? nullptr : p.handp.data(), rank, size);
    double* q = p.xqp != nullptr ? AcquireArray(p.xqp) : nullptr;
    const std::vector<double> petsc_gathered = Gather(p, q, rank, size);
    if (q != nullptr) ReleaseArray(p.xqp, q);
    if (rank == 0) {
      const Verdict v = Check(p, gathered, hand_gathered, petsc_gathered, o, h, cfg);
      Report(o, p, h, cfg, v, load0, size);
      if (!o.csv.empty()) WriteCsv(o, p, h, cfg);
      bad = v.ok ? 0 : 1;
    }
  } else if (rank == 0) {
    std::fprintf(stderr, "unknown method %s or no stability limit\n", o.method.c_str());
  }
  MPI_Bcast(&bad, 1, MPI_INT, 0, MPI_COMM_WORLD);
  Teardown(&p);
#if defined(CEODE_HAVE_PETSC)
  PetscFinalize();
#endif
  MPI_Finalize();
  return bad;
}
