// The Q4 cantilever plate of bench/fe_plate_model.h (the linear FE scene) partitioned over
// MPI ranks (docs/mpi.md), with the interface of bench/mpi_membrane_model.h so that
// bench/mpi_membrane.cpp drives either (built as mpi_fe_plate with CEODE_MPI_FE_PLATE).
//
// The plate's free nodes are numbered column by column along the short edge, 2 (ny + 1) DOFs a
// column, so a block of whole node columns is a contiguous DOF range: one block per rank, one
// NVECTOR_PARALLEL local part. K's rows of a column reach only the columns beside it, so f needs
// one halo column from each neighbour block: exchanged with non-blocking sends, overlapped with the
// rows that need no halo. Each rank keeps only its rows of K (columns shifted to its range);
// every row is summed with the same entries in the same order as fe::Accel, so a distributed run
// is bitwise equal to a serial one.
//
// The global K is assembled on every rank and cut down (simple, and the assembly is not what is
// measured); a cluster code assembles its own elements only. The step comes from a Gershgorin
// bound of M^{-1} K, the guaranteed bound an explicit FE code uses (docs/theory.md; the estimate
// against the exact omega_max is wp_fe_plate's part 1).
#ifndef CEODE_BENCH_MPI_FE_PLATE_MODEL_H_
#define CEODE_BENCH_MPI_FE_PLATE_MODEL_H_

#include <mpi.h>
#include <nvector/nvector_parallel.h>
#include <nvector/nvector_serial.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "fe_plate_model.h"
#include "mpi_partition.h"

namespace fe_strip {

// One rank's block: free node columns [col0, col0 + ncols) (0-based among the nx free columns),
// DOFs [off, off + len), and its rows of K.
struct Strip {
  MPI_Comm comm = MPI_COMM_NULL;  // MPI_COMM_NULL: the whole plate on one NVECTOR_SERIAL
  int rank = 0;
  int size = 1;
  int nx = 0;  // elements along the plate (free node columns)
  int ny = 0;  // elements across
  int col0 = 0;
  int ncols = 0;
  int nactive = 1;  // ranks that own columns: min(size, nx)
  long off = 0;
  long len = 0;
  long halo = 0;             // DOFs of one node column, 2 (ny + 1)
  long n = 0;                // global DOFs
  std::vector<long> rowptr;  // this block's rows of K; columns relative to off
  std::vector<int> col;
  std::vector<double> val;
  std::vector<double> invm;
  double omega_bound = 0;  // Gershgorin bound of omega_max (whole plate)
  std::vector<double> lo;  // [halo column below | first two own columns]
  std::vector<double> hi;  // [last two own columns | halo column above]
  long nexchange = 0;      // halo exchanges done
  bool exchange = true;    // false: stale halo columns (a negative control only)
};

// The balanced column partition: rank owns free node columns [*c0, *c0 + *nc).
inline void ColumnRange(int nx, int size, int rank, int* c0, int* nc) {
  mpi_partition::BalancedRange(nx, size, rank, c0, nc);
}

// omega_max^2 <= max_r sum_q |K_rq| / m_r (Gershgorin on M^{-1} K).
inline double GershgorinOmega(const fe::Plate& p) {
  double w2 = 0;
  for (int r = 0; r < p.n; ++r) {
    double s = 0;
    for (int q = p.rowptr[r]; q < p.rowptr[r + 1]; ++q) s += std::fabs(p.val[q]);
    w2 = std::max(w2, s * p.invm[r]);
  }
  return std::sqrt(w2);
}

// The plate for about n DOFs: a 4 ny x ny mesh, 8 ny (ny + 1) DOFs.
inline int AcrossFor(long n) {
  return std::max(2, static_cast<int>(std::lround(std::sqrt(static_cast<double>(n) / 8))));
}

inline Strip MakeStrip(MPI_Comm comm, long n_target) {
  Strip s;
  s.comm = comm;
  if (comm != MPI_COMM_NULL) {
    MPI_Comm_rank(comm, &s.rank);
    MPI_Comm_size(comm, &s.size);
  }
  s.ny = AcrossFor(n_target);
  s.nx = 4 * s.ny;
  const fe::Plate p = fe::MakePlate(s.nx, s.ny);
  s.n = p.n;
  s.halo = 2L * (s.ny + 1);
  s.nactive = std::min(s.size, s.nx);
  ColumnRange(s.nx, s.size, s.rank, &s.col0, &s.ncols);
  s.off = s.col0 * s.halo;
  s.len = s.ncols * s.halo;
  s.rowptr.assign(1, 0);
  for (long r = s.off; r < s.off + s.len; ++r) {
    for (int q = p.rowptr[r]; q < p.rowptr[r + 1]; ++q) {
      s.col.push_back(static_cast<int>(p.col[q] - s.off));
      s.val.push_back(p.val[q]);
    }
    s.rowptr.push_back(static_cast<long>(s.col.size()));
    s.invm.push_back(p.invm[r]);
  }
  s.omega_bound = GershgorinOmega(p);
  s.lo.assign(static_cast<size_t>(3 * s.halo), 0.0);
  s.hi.assign(static_cast<size_t>(3 * s.halo), 0.0);
  return s;
}

inline long LocalLength(const Strip& s) { return s.len; }
inline long GlobalLength(const Strip& s) { return s.n; }

// Rank r's DOF range, for gathering a distributed state.
inline void Range(const Strip& s, int r, long* off, long* len) {
  int c0 = 0, nc = 0;
  ColumnRange(s.nx, s.size, r, &c0, &nc);
  *off = c0 * s.halo;
  *len = nc * s.halo;
}

inline std::string Describe(const Strip& s) {
  return "Q4 cantilever plate " + std::to_string(s.nx) + " x " + std::to_string(s.ny) + " elements";
}

// Rows [r0, r1) of a = -M^{-1} K x, x at column c (relative to off) in buf[c + shift].
template <bool kShifted>
void RowsOf(const Strip& s, const double* buf, long shift, long r0, long r1, double* a) {
  const long* rp = s.rowptr.data();
  const int* ci = s.col.data();
  const double* kv = s.val.data();
  for (long r = r0; r < r1; ++r) {
    double sum = 0;
    for (long q = rp[r]; q < rp[r + 1]; ++q) sum += kv[q] * buf[kShifted ? ci[q] + shift : ci[q]];
    a[r] = -s.invm[r] * sum;
  }
}

// Post the halo receives and sends of this block's first and last node columns (tag 0:
// travelling up the rank order, tag 1: down). Returns the number of requests.
inline int StartHalo(Strip* s, const double* u, MPI_Request* req) {
  int n = 0;
  if (!s->exchange || s->comm == MPI_COMM_NULL) return 0;
  const int h = static_cast<int>(s->halo);
  if (s->rank > 0 && s->ncols > 0) {
    MPI_Irecv(s->lo.data(), h, MPI_DOUBLE, s->rank - 1, 0, s->comm, &req[n++]);
    MPI_Isend(u, h, MPI_DOUBLE, s->rank - 1, 1, s->comm, &req[n++]);
  }
  if (s->rank + 1 < s->nactive) {
    MPI_Irecv(s->hi.data() + 2 * s->halo, h, MPI_DOUBLE, s->rank + 1, 1, s->comm, &req[n++]);
    MPI_Isend(u + s->len - s->halo, h, MPI_DOUBLE, s->rank + 1, 0, s->comm, &req[n++]);
  }
  if (n > 0) ++s->nexchange;
  return n;
}

// M x'' = -K x on the block: the rows that need no halo while the halo columns travel, then the
// first and the last node column through windows [halo | own] and [own | halo].
inline int Accel(Strip* s, const double* u, double* a) {
  const long h = s->halo;
  const long len = s->len;
  if (len == 0) return 0;
  if (s->ncols < 2) return -1;  // the two edge columns would overlap: too many ranks
  MPI_Request req[4];
  const int nreq = StartHalo(s, u, req);
  RowsOf<false>(*s, u, 0, h, len - h, a);
  std::copy(u, u + 2 * h, s->lo.begin() + h);
  std::copy(u + len - 2 * h, u + len, s->hi.begin());
  // Only req[0, nreq) were started, and only they are waited for.
  if (nreq > 0 &&
      MPI_Waitall(nreq, req, MPI_STATUSES_IGNORE) != MPI_SUCCESS) {  // NOLINT(*MPI-Checker)
    return -1;
  }
  RowsOf<true>(*s, s->lo.data(), h, 0, h, a);
  RowsOf<true>(*s, s->hi.data(), 2 * h - len, len - h, len, a);
  return 0;
}

// CEODE's right-hand side: Accel on the vectors' local arrays.
inline int Rhs(sunrealtype, N_Vector x, N_Vector, N_Vector f, void* data) {
  return Accel(static_cast<Strip*>(data), N_VGetArrayPointer(x), N_VGetArrayPointer(f));
}

// The step's frequency: the Gershgorin bound (above the exact omega_max, so h is safe).
inline double OmegaMax(const Strip& s) { return s.omega_bound; }

// x0: the transverse displacement (X / Lx)^2 of a beam-like bend (unit tip), u_x = 0; v0 = 0.
inline void InitialState(const Strip& s, double* x, double* v) {
  for (long k = 0; k < s.len; ++k) {
    const long d = s.off + k;
    const long column = d / s.halo + 1;  // node column i >= 1 (i = 0 is clamped)
    const double X = static_cast<double>(column) / s.nx;
    x[k] = d % 2 == 1 ? X * X : 0.0;
    v[k] = 0;
  }
}

// No closed-form solution on this model: wp_fe_plate checks it against its modal reference. Here
// the state must stay finite and bounded by the initial tip deflection's order (a stable run of a
// linear undamped plate started at rest keeps its energy): max |x| <= 2. Returns max |x| / 2.
inline double Accuracy(const Strip& s, const double* x, long /*steps*/, double /*h*/,
                       bool /*discrete*/, double* tol, const char** what) {
  double m = 0;
  for (long k = 0; k < s.n; ++k) m = std::isfinite(x[k]) ? std::max(m, std::fabs(x[k])) : HUGE_VAL;
  *tol = 1;
  *what = "max |x| / 2 (stays bounded: no closed form on this model, see wp_fe_plate)";
  return m / 2;
}

}  // namespace fe_strip

#endif  // CEODE_BENCH_MPI_FE_PLATE_MODEL_H_
