// -----------------------------------------------------------------------------
// chain_scaling: the cost of one CEODE step against the size of the model, on
// the chain of N pendulums of chain_model.h (index-3 DAE, docs/theory.md
// section 8), through the sparse saddle-point path (CSR + KLU).
//
// Each run takes 1000 steps of h = 1e-4 s from rest at 60 deg, so that the time
// per step compares between sizes; h stays inside the stability limit of
// central differences (Omega_max = 2) for the chain's highest transverse
// frequency, about 2 N sqrt(g/L) rad/s: Omega ~ 0.6 at N = 1000, ~ 1.9 at
// N = 3000 (N = 10000 would need a smaller h). Method: CEODE G3_CD (central
// differences; with constraints this is SHAKE), the (n+nc) x (n+nc) CSR
// saddle-point matrix factored by SUNLinSol_KLU, G(x) filled as an nc x n CSR
// SUNSparseMatrix by the constraint Jacobian callback. Timing and rows: the
// harness of wp_common.h (CPU seconds per run, scene chain_dae).
//
// Checks (exit code): every run succeeds, the drift of every run is
// <= 1e-10 l^2 (position round-off alone is ~1e-16 |p| l, ~1e-13 l^2 at
// N = 1000), and the least-squares slope of log(time per step) against log N is
// <= 1.3. Sizes N = 10, 30, 100, 300, 1000 (--full adds 3000; --quick stops at
// 100).
// -----------------------------------------------------------------------------
#include "chain_model.h"

namespace {

double LsqSlope(const std::vector<double>& x, const std::vector<double>& y) {
  const double n = static_cast<double>(x.size());
  double mx = 0, my = 0, sxy = 0, sxx = 0;
  for (size_t k = 0; k < x.size(); ++k) mx += x[k] / n, my += y[k] / n;
  for (size_t k = 0; k < x.size(); ++k) {
    sxy += (x[k] - mx) * (y[k] - my);
    sxx += (x[k] - mx) * (x[k] - mx);
  }
  return sxy / sxx;
}

}  // namespace

int main(int argc, char** argv) {
  const wp::Args args = wp::ParseArgs(argc, argv);
  constexpr double kH = 1e-4;
  constexpr long kSteps = 1000;
  std::vector<long> sizes = {10, 30, 100};
  if (!args.quick) sizes.insert(sizes.end(), {300, 1000});
  if (args.full) sizes.push_back(3000);
  SUNContext ctx = nullptr;
  if (SUNContext_Create(SUN_COMM_NULL, &ctx) != 0) return 1;
  std::printf("Planar chain of N unit point masses, links L/N, index-3 DAE, CEODE G3_CD + KLU\n");
  std::printf("%ld steps of h = %g s from rest at 60 deg\n\n", kSteps, kH);
  wp::Table table("chain_dae", args.csv);
  std::vector<double> lx, ly;
  int bad = 0;
  for (long N : sizes) {
    chain::Chain c = chain::Make(N);
    const wp::Problem p = chain::Problem(&c, kH * static_cast<double>(kSteps), false);
    const std::string config = "N=" + std::to_string(N) + " G3_CD";
    wp::Outcome o;
    if (!wp::MeasureCeode(&table, ctx, p, "G3_CD", kH, false, config, &o)) {
      ++bad;
      continue;
    }
    if (!(o.drift <= 1e-10 * c.l * c.l)) {
      ++bad;
      std::printf("  <-- N = %ld: drift above 1e-10 l^2\n", N);
    }
    lx.push_back(std::log(static_cast<double>(N)));
    ly.push_back(std::log(table.rows().back().seconds / static_cast<double>(o.steps)));
  }
  const double slope = lx.size() >= 2 ? LsqSlope(lx, ly) : 99.0;
  std::printf("\nlog-log slope of CPU time per step against N (least squares): %.3f\n", slope);
  if (slope > 1.3) {
    ++bad;
    std::printf("slope above 1.3: the step cost grows faster than linearly\n");
  }
  SUNContext_Free(&ctx);
  std::printf("scaling: %d runs failed or checks off\n", bad);
  return bad == 0 ? 0 : 1;
}
