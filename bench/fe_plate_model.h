// -----------------------------------------------------------------------------
// fe_plate_model.h: a 2-D linear elastic finite-element cantilever for the
// structural scenes (bench/fe_plate/, bench/mpi/, test/test_frequency_bound.cpp).
//
// A plate Lx x Ly of thickness t in plane stress (E, nu, rho), meshed by nx x ny
// equal bilinear (Q4) elements, clamped along x = 0. The element stiffness is
// integrated by 2 x 2 Gauss points; the mass is row-sum lumped (a quarter of the
// element mass at each node). K is assembled once, straight into CSR (the
// regular mesh's 3 x 3 node stencil gives each row its columns, so there is no
// triplet list even at 10^6 DOF). Free nodes are numbered column by column along
// the short edge (node (i, j), i >= 1, gets index (i - 1)(ny + 1) + j, DOFs 2k
// and 2k + 1), which keeps the bandwidth at about 2 (ny + 2).
//
// Also here: the Q4 element's own matrices (for the element-by-element bound of
// explicit FE codes: omega_max of the assembly is at most the largest element
// frequency with the element's lumped mass, and for this uniform mesh every
// element is the same) and the accelerations a = -M^{-1} (K x + C v) with
// Rayleigh damping C = a_m M + b_k K.
// -----------------------------------------------------------------------------
#ifndef CEODE_BENCH_FE_PLATE_MODEL_H_
#define CEODE_BENCH_FE_PLATE_MODEL_H_

#include <array>
#include <cmath>
#include <vector>

namespace fe {

using Mat8 = std::array<std::array<double, 8>, 8>;

struct Plate {
  int nx = 0, ny = 0;
  double Lx = 4, Ly = 1, thick = 1, E = 1, nu = 0.3, rho = 1;
  int n = 0;                      // free DOFs
  std::vector<int> rowptr;        // CSR of K, n + 1 entries
  std::vector<int> col;           // column of each entry (sorted within a row)
  std::vector<double> val;        // K entries
  std::vector<double> mass;       // lumped mass of each DOF
  std::vector<double> invm;       // 1 / mass
  Mat8 ke{};                      // element stiffness (every element is the same)
  double me = 0;                  // lumped mass of one element node
  double damp_m = 0, damp_k = 0;  // Rayleigh C = damp_m M + damp_k K
};

// Q4 plane-stress stiffness of a dx x dy element, nodes (0,0), (dx,0), (dx,dy),
// (0,dy), DOFs (u0, v0, u1, v1, ...), 2 x 2 Gauss points.
inline Mat8 Q4Stiffness(double dx, double dy, double E, double nu, double thick) {
  const double c = E / (1 - nu * nu);
  const double D[3][3] = {{c, c * nu, 0}, {c * nu, c, 0}, {0, 0, c * (1 - nu) / 2}};
  const double xi_n[4] = {-1, 1, 1, -1}, eta_n[4] = {-1, -1, 1, 1};
  const double g = 1 / std::sqrt(3.0);
  Mat8 k{};
  for (double xi : {-g, g}) {
    for (double eta : {-g, g}) {
      double B[3][8] = {};
      for (int a = 0; a < 4; ++a) {
        const double dNx = 0.25 * xi_n[a] * (1 + eta * eta_n[a]) * 2 / dx;
        const double dNy = 0.25 * eta_n[a] * (1 + xi * xi_n[a]) * 2 / dy;
        B[0][2 * a] = dNx;
        B[1][2 * a + 1] = dNy;
        B[2][2 * a] = dNy;
        B[2][2 * a + 1] = dNx;
      }
      const double w = thick * dx * dy / 4;  // Gauss weights 1, Jacobian dx dy / 4
      for (int i = 0; i < 8; ++i) {
        for (int j = 0; j < 8; ++j) {
          double s = 0;
          for (int p = 0; p < 3; ++p) {
            for (int q = 0; q < 3; ++q) s += B[p][i] * D[p][q] * B[q][j];
          }
          k[i][j] += w * s;
        }
      }
    }
  }
  return k;
}

// Free-DOF index of node (i, j), -1 on the clamped edge.
inline int NodeIndex(const Plate& p, int i, int j) {
  return i == 0 ? -1 : (i - 1) * (p.ny + 1) + j;
}

// Local number (0..3) of node (i, j) in element (ei, ej), -1 when not in it.
inline int LocalNode(int ei, int ej, int i, int j) {
  const int di = i - ei, dj = j - ej;
  if (di < 0 || di > 1 || dj < 0 || dj > 1) return -1;
  static const int kLocal[2][2] = {{0, 3}, {1, 2}};  // [di][dj]
  return kLocal[di][dj];
}

// K(row DOFs of node a, column DOFs of node b), summed over shared elements.
inline void NodeBlock(const Plate& p, int ia, int ja, int ib, int jb, double blk[2][2]) {
  blk[0][0] = blk[0][1] = blk[1][0] = blk[1][1] = 0;
  for (int ei = ia - 1; ei <= ia; ++ei) {
    for (int ej = ja - 1; ej <= ja; ++ej) {
      if (ei < 0 || ei >= p.nx || ej < 0 || ej >= p.ny) continue;
      const int la = LocalNode(ei, ej, ia, ja), lb = LocalNode(ei, ej, ib, jb);
      if (la < 0 || lb < 0) continue;
      for (int r = 0; r < 2; ++r) {
        for (int c = 0; c < 2; ++c) blk[r][c] += p.ke[2 * la + r][2 * lb + c];
      }
    }
  }
}

// Number of elements touching node (i, j).
inline int NodeElements(const Plate& p, int i, int j) {
  const int ci = (i > 0) + (i < p.nx), cj = (j > 0) + (j < p.ny);
  return ci * cj;
}

inline Plate MakePlate(int nx, int ny, double Lx = 4, double Ly = 1) {
  Plate p;
  p.nx = nx;
  p.ny = ny;
  p.Lx = Lx;
  p.Ly = Ly;
  const double dx = Lx / nx, dy = Ly / ny;
  p.ke = Q4Stiffness(dx, dy, p.E, p.nu, p.thick);
  p.me = p.rho * p.thick * dx * dy / 4;
  p.n = 2 * nx * (ny + 1);
  p.rowptr.assign(1, 0);
  p.mass.resize(p.n);
  p.col.reserve(18L * p.n);
  p.val.reserve(18L * p.n);
  for (int i = 1; i <= nx; ++i) {
    for (int j = 0; j <= ny; ++j) {
      for (int r = 0; r < 2; ++r) {
        for (int ib = i - 1; ib <= i + 1; ++ib) {
          for (int jb = j - 1; jb <= j + 1; ++jb) {
            if (ib < 1 || ib > nx || jb < 0 || jb > ny) continue;
            double blk[2][2];
            NodeBlock(p, i, j, ib, jb, blk);
            for (int c = 0; c < 2; ++c) {
              p.col.push_back(2 * NodeIndex(p, ib, jb) + c);
              p.val.push_back(blk[r][c]);
            }
          }
        }
        p.rowptr.push_back(static_cast<int>(p.col.size()));
        p.mass[2 * NodeIndex(p, i, j) + r] = p.me * NodeElements(p, i, j);
      }
    }
  }
  p.invm.resize(p.n);
  for (int k = 0; k < p.n; ++k) p.invm[k] = 1 / p.mass[k];
  return p;
}

// y = K x.
inline void KTimes(const Plate& p, const double* x, double* y) {
  const int* rp = p.rowptr.data();
  const int* ci = p.col.data();
  const double* kv = p.val.data();
  for (int r = 0; r < p.n; ++r) {
    double s = 0;
    for (int q = rp[r]; q < rp[r + 1]; ++q) s += kv[q] * x[ci[q]];
    y[r] = s;
  }
}

// a = -M^{-1} K x: the undamped accelerations, one pass over K.
inline void Accel(const Plate& p, const double* x, double* a) {
  const int* rp = p.rowptr.data();
  const int* ci = p.col.data();
  const double* kv = p.val.data();
  const double* im = p.invm.data();
  for (int r = 0; r < p.n; ++r) {
    double s = 0;
    for (int q = rp[r]; q < rp[r + 1]; ++q) s += kv[q] * x[ci[q]];
    a[r] = -im[r] * s;
  }
}

// a = -M^{-1} (K (x + b_k v)) - a_m v: Rayleigh damping in the same pass.
inline void AccelDamped(const Plate& p, const double* x, const double* v, double* a) {
  const int* rp = p.rowptr.data();
  const int* ci = p.col.data();
  const double* kv = p.val.data();
  const double* im = p.invm.data();
  const double bk = p.damp_k, am = p.damp_m;
  for (int r = 0; r < p.n; ++r) {
    double s = 0;
    if (bk != 0) {
      for (int q = rp[r]; q < rp[r + 1]; ++q) s += kv[q] * (x[ci[q]] + bk * v[ci[q]]);
    } else {
      for (int q = rp[r]; q < rp[r + 1]; ++q) s += kv[q] * x[ci[q]];
    }
    a[r] = -im[r] * s - am * v[r];
  }
}

}  // namespace fe

#endif  // CEODE_BENCH_FE_PLATE_MODEL_H_
