// -----------------------------------------------------------------------------
// fe_plate_c_scene: the C side of the Python benchmarks and tests on the Q4 cantilever plate of
// bench/fe_plate_model.h (the model of wp_fe_plate's scaling part).
//
//   fe_plate_c_scene export NX NY FILE
//       writes the model to FILE for numpy (bench/python/problem_plate.py reads it):
//       "CEFEPLT1", int64 n, int64 nnz, then int32 rowptr[n + 1], int32 col[nnz],
//       float64 val[nnz], float64 mass[n] (row-sum lumped), float64 x0[n] (the scaling scene's
//       start), float64 probe[n] (probe_k = sin(k + 1)) and float64 K probe[n]: the reader checks
//       that its own sparse product reproduces the last array.
//   fe_plate_c_scene run NX NY SET H STEPS FILE
//       CEODE through the C API from (x0, 0): set SET, fixed step H, guard off, f declared
//       velocity-independent, STEPS single steps (CE_ONE_STEP); writes float64 t, x[n], v[n].
//   fe_plate_c_scene time NX NY SET H CHUNK REPS
//       the same integrator, one untimed chunk of CHUNK steps (start, warm caches), then REPS
//       chunks each to t + CHUNK H (CE_NORMAL); prints one line per chunk:
//       "chunk <steps> <cpu seconds per step>" (process CPU clock), and the guard's stable step
//       of SET at safety 1 as "stable_step <h>".
//   fe_plate_c_scene serve NX NY SET H CHUNK
//       the same after the untimed chunk, one timed chunk for each line read on stdin (the
//       Python benchmark alternates its chunks with these, chunk by chunk).
// Exit code 0 when every CEODE call succeeded, 2 on bad arguments.
// -----------------------------------------------------------------------------
#include <ceode/ceode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <string>
#include <vector>

#include "ceode_sundials_compat.h"  // SUN_COMM_NULL on SUNDIALS 6.4
#include "fe_plate_model.h"

namespace {

using Vec = std::vector<double>;

double CpuNow() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// The start of wp_fe_plate's scaling scene: a linear ramp of the transverse DOFs.
Vec StartState(const fe::Plate& p) {
  Vec x(p.n, 0.0);
  const int pairs = p.n / 2;
  for (int j = 0; 2 * j + 1 < p.n; ++j) x[2 * j + 1] = 1e-3 * (j + 1.0) / pairs;
  return x;
}

int Accel(sunrealtype, N_Vector x, N_Vector, N_Vector a, void* user) {
  fe::Accel(*static_cast<const fe::Plate*>(user), N_VGetArrayPointer(x), N_VGetArrayPointer(a));
  return 0;
}

bool Failed(int flag, const char* call) {
  if (flag >= 0) return false;
  std::fprintf(stderr, "%s failed with flag %d (%s)\n", call, flag, CEodeGetReturnFlagName(flag));
  return true;
}

template <class T>
void Write(FILE* f, const T* data, size_t n) {
  std::fwrite(data, sizeof(T), n, f);
}

int Export(const fe::Plate& p, const char* path) {
  FILE* f = std::fopen(path, "wb");
  if (f == nullptr) {
    std::fprintf(stderr, "cannot write %s\n", path);
    return 1;
  }
  const int64_t head[2] = {p.n, static_cast<int64_t>(p.val.size())};
  std::fwrite("CEFEPLT1", 1, 8, f);
  Write(f, head, 2);
  Write(f, p.rowptr.data(), p.rowptr.size());
  Write(f, p.col.data(), p.col.size());
  Write(f, p.val.data(), p.val.size());
  Write(f, p.mass.data(), p.mass.size());
  const Vec x0 = StartState(p);
  Write(f, x0.data(), x0.size());
  Vec probe(p.n), kp(p.n);
  for (int k = 0; k < p.n; ++k) probe[k] = std::sin(k + 1.0);
  fe::KTimes(p, probe.data(), kp.data());
  Write(f, probe.data(), probe.size());
  Write(f, kp.data(), kp.size());
  const bool ok = std::fclose(f) == 0;
  std::printf("%d DOF, %zu nonzeros written to %s\n", p.n, p.val.size(), path);
  return ok ? 0 : 1;
}

// One CEODE memory on the plate: set, fixed step h, guard off, f velocity-independent.
struct Run {
  SUNContext ctx = nullptr;
  void* mem = nullptr;
  N_Vector x = nullptr, v = nullptr, m = nullptr;
  ~Run() {
    CEodeFree(&mem);
    N_VDestroy(x);
    N_VDestroy(v);
    N_VDestroy(m);
    SUNContext_Free(&ctx);
  }
  bool Start(fe::Plate* p, const char* set, double h) {
    if (SUNContext_Create(SUN_COMM_NULL, &ctx) != 0) return false;
    x = N_VNew_Serial(p->n, ctx);
    v = N_VNew_Serial(p->n, ctx);
    m = N_VNew_Serial(p->n, ctx);
    mem = CEodeCreate(ctx);
    if (x == nullptr || v == nullptr || m == nullptr || mem == nullptr) return false;
    const Vec x0 = StartState(*p);
    std::copy(x0.begin(), x0.end(), N_VGetArrayPointer(x));
    N_VConst(0.0, v);
    std::copy(p->mass.begin(), p->mass.end(), N_VGetArrayPointer(m));
    return !Failed(CEodeInit(mem, Accel, 0.0, x, v), "CEodeInit") &&
           !Failed(CEodeSetUserData(mem, p), "CEodeSetUserData") &&
           !Failed(CEodeSetMethodByName(mem, set), "CEodeSetMethodByName") &&
           !Failed(CEodeSetFixedStep(mem, h), "CEodeSetFixedStep") &&
           !Failed(CEodeSetVelocityDependence(mem, SUNFALSE), "CEodeSetVelocityDependence") &&
           !Failed(CEodeSetGuardMass(mem, m), "CEodeSetGuardMass") &&
           !Failed(CEodeSetMaxNumSteps(mem, 100000000L), "CEodeSetMaxNumSteps");
  }
  long Steps() const {
    long n = 0;
    CEodeGetNumSteps(mem, &n);
    return n;
  }
};

int RunSteps(fe::Plate* p, const char* set, double h, long steps, const char* path) {
  Run r;
  if (!r.Start(p, set, h) ||
      Failed(CEodeSetStabilityGuard(r.mem, CE_GUARD_OFF, 0), "CEodeSetStabilityGuard")) {
    return 1;
  }
  double t = 0;
  const double tfar = h * static_cast<double>(steps + 10);
  for (long k = 0; k < steps; ++k) {
    if (Failed(CEodeEvolve(r.mem, tfar, r.x, r.v, &t, CE_ONE_STEP), "CEodeEvolve")) return 1;
  }
  FILE* f = std::fopen(path, "wb");
  if (f == nullptr) return 1;
  Write(f, &t, 1);
  Write(f, N_VGetArrayPointer(r.x), p->n);
  Write(f, N_VGetArrayPointer(r.v), p->n);
  const bool ok = std::fclose(f) == 0;
  std::printf("%s: %ld steps of %.17g to t = %.17g written to %s\n", set, r.Steps(), h, t, path);
  return ok ? 0 : 1;
}

// One chunk: CE_NORMAL to t + chunk h; *per_step gets the CPU seconds per step taken.
bool Chunk(const Run& r, double h, long chunk, double* t, double* per_step) {
  const long s0 = r.Steps();
  const double c0 = CpuNow();
  if (Failed(CEodeEvolve(r.mem, *t + static_cast<double>(chunk) * h, r.x, r.v, t, CE_NORMAL),
             "CEodeEvolve")) {
    return false;
  }
  *per_step = (CpuNow() - c0) / static_cast<double>(r.Steps() - s0);
  return true;
}

bool StartTimed(fe::Plate* p, const char* set, double h, long chunk, Run* r, double* t) {
  sunrealtype hstab = 0;
  double per_step = 0;
  if (!r->Start(p, set, h) ||
      Failed(CEodeGetStableStep(r->mem, 1.0, &hstab), "CEodeGetStableStep") ||
      Failed(CEodeSetStabilityGuard(r->mem, CE_GUARD_OFF, 0), "CEodeSetStabilityGuard")) {
    return false;
  }
  std::printf("stable_step %.17g\n", hstab);
  return Chunk(*r, h, chunk, t, &per_step);  // untimed: the start, caches warm
}

int Time(fe::Plate* p, const char* set, double h, long chunk, int reps) {
  Run r;
  double t = 0, per_step = 0;
  if (!StartTimed(p, set, h, chunk, &r, &t)) return 1;
  for (int k = 0; k < reps; ++k) {
    if (!Chunk(r, h, chunk, &t, &per_step)) return 1;
    std::printf("chunk %ld %.6e\n", chunk, per_step);
  }
  std::fflush(stdout);
  return 0;
}

// One timed chunk for every line read on stdin, until its end: the caller interleaves these
// chunks with its own, each side idle while the other runs.
int Serve(fe::Plate* p, const char* set, double h, long chunk) {
  Run r;
  double t = 0, per_step = 0;
  if (!StartTimed(p, set, h, chunk, &r, &t)) return 1;
  std::fflush(stdout);
  char line[64];
  while (std::fgets(line, sizeof line, stdin) != nullptr) {
    if (!Chunk(r, h, chunk, &t, &per_step)) return 1;
    std::printf("chunk %ld %.6e\n", chunk, per_step);
    std::fflush(stdout);
  }
  return 0;
}

int Usage(const char* prog) {
  std::fprintf(stderr,
               "usage: %s export NX NY FILE | run NX NY SET H STEPS FILE | "
               "time NX NY SET H CHUNK REPS | serve NX NY SET H CHUNK\n",
               prog);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 5) return Usage(argv[0]);
  const std::string mode = argv[1];
  const int nx = std::atoi(argv[2]), ny = std::atoi(argv[3]);
  if (nx < 1 || ny < 1) return Usage(argv[0]);
  fe::Plate p = fe::MakePlate(nx, ny);
  if (mode == "export" && argc == 5) return Export(p, argv[4]);
  if (argc != 8 && !(mode == "serve" && argc == 7)) return Usage(argv[0]);
  const double h = std::atof(argv[5]);
  const long count = std::atol(argv[6]);
  if (!(h > 0) || count < 1) return Usage(argv[0]);
  if (mode == "serve") return Serve(&p, argv[4], h, count);
  if (mode == "run") return RunSteps(&p, argv[4], h, count, argv[7]);
  if (mode == "time") return Time(&p, argv[4], h, count, std::atoi(argv[7]));
  return Usage(argv[0]);
}
