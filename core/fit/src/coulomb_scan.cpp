#include "coulomb_scan.hpp"

#include <cmath>
#include <cstring>
#include <memory>
#include <span>

#include "vector_clones.hpp"

namespace spindown::friction {
namespace {

// Weighted sums of the straight line y ≈ u0 − β·τ over the samples added so far, and the two
// least-squares lines they give. Each is an optimum, so its SSE is Σw·y² minus a gain q/d.
struct LineSums {
  double w = 0, t = 0, tt = 0, y = 0, ty = 0;  // Σw, Σw·τ, Σw·τ², Σw·y, Σw·τ·y

  void add(double wi, double wyi, double ti) { w += wi, t += wi * ti, tt += wi * ti * ti, y += wyi, ty += wyi * ti; }
  // Both parameters free: [Σw −Σwτ; −Σwτ Σwτ²]·(u0, β) = (Σwy, −Σwτy), u0 = U/det, β = B/det.
  double det() const { return w * tt - t * t; }
  double u() const { return tt * y - t * ty; }
  double b() const { return t * y - w * ty; }
  double plain_gain_times_det() const { return tt * y * y - 2 * t * y * ty + w * ty * ty; }
  Theta plain() const { return {u() / det(), 0.0, b() / det()}; }
  // Stopped exactly at te (u0 = β·te): β = Σw·y·(te−τ) / Σw·(te−τ)², gain num²/den.
  double edge_num(double te) const { return te * y - ty; }
  double edge_den(double te) const { return te * te * w - 2 * te * t + tt; }
  Theta edge(double te) const {
    const double beta = edge_num(te) / edge_den(te);
    return {beta * te, 0.0, beta};
  }
};

// LineSums over samples [lo, hi) in one vectorised pass (four lanes: the order of the additions
// differs from adding them one by one only in rounding).
using LineLanes = Lanes<5>;  // Σw, Σw·τ, Σw·τ², Σw·y, Σw·τ·y
SPINDOWN_LANE_BODY inline void add_line_lanes(LineLanes& acc, const double* t, const double* ws, const double* wys,
                                              std::size_t lo, std::size_t hi) {
  for_each_in_lanes(lo, hi, [&](std::size_t i, std::size_t l) SPINDOWN_LANE_BODY {
    const double wt = ws[i] * t[i];
    auto& a = acc.sum;
    a[0][l] += ws[i], a[1][l] += wt, a[2][l] += wt * t[i], a[3][l] += wys[i], a[4][l] += wys[i] * t[i];
  });
}
LineSums line_total(const LineLanes& acc) { return {acc.total(0), acc.total(1), acc.total(2), acc.total(3), acc.total(4)}; }

SPINDOWN_VECTOR_CLONES LineSums line_sums(std::span<const double> tau, std::span<const double> w,
                                          std::span<const double> wy, std::size_t lo, std::size_t hi) {
  LineLanes acc;
  add_line_lanes(acc, tau.data(), w.data(), wy.data(), lo, hi);
  return line_total(acc);
}

// Counted from sample 0, sample i adds to lane i mod 4 in order, so the lanes over [0, m) are
// those over [0, c), c any multiple of 4 up to m, plus the samples [c, m). The Coulomb scan needs
// the sums up to the hint and then up to an earlier count: line_sums(0, hi) keeps its lanes
// every checkpoint_every samples (checkpoint k holds [0, k·checkpoint_every)), and the shorter
// prefix continues from one, bit for bit what line_sums(0, m) gives, instead of starting again.
constexpr std::size_t checkpoint_every = 64;  // a multiple of the four lanes
constexpr std::size_t checkpoint_size = sizeof(LineLanes::sum) / sizeof(double);  // doubles per checkpoint
SPINDOWN_VECTOR_CLONES LineSums line_sums_with_checkpoints(std::span<const double> tau, std::span<const double> w,
                                                           std::span<const double> wy, std::size_t hi,
                                                           double* checkpoints) {
  LineLanes acc;
  for (std::size_t lo = 0, k = 0; lo < hi; lo += checkpoint_every, ++k) {
    std::memcpy(checkpoints + k * checkpoint_size, acc.sum, sizeof acc.sum);
    add_line_lanes(acc, tau.data(), w.data(), wy.data(), lo, std::min(lo + checkpoint_every, hi));
  }
  return line_total(acc);
}
SPINDOWN_VECTOR_CLONES LineSums line_sums_from_checkpoint(std::span<const double> tau, std::span<const double> w,
                                                          std::span<const double> wy, std::size_t m,
                                                          const double* checkpoints) {
  const std::size_t k = m / checkpoint_every;
  LineLanes acc;
  std::memcpy(acc.sum, checkpoints + k * checkpoint_size, sizeof acc.sum);
  add_line_lanes(acc, tau.data(), w.data(), wy.data(), k * checkpoint_every, m);
  return line_total(acc);
}

}  // namespace

std::optional<Theta> coulomb_by_line_scan(const Evaluator& eval, std::size_t hint, int& passes) {
  const std::span<const double> tau = eval.tau(), w = eval.weights(), wy = eval.weighted_readings();
  const std::size_t n = tau.size();
  if (!eval.sorted() || n < 3) return std::nullopt;
  ++passes;
  // The best candidate has the largest gain q/d, compared as q·d_best > q_best·d (d > 0): no
  // division per m. The winner's sums are kept; its parameters come from them at the end.
  LineSums sums, best;
  double best_q = 0, best_d = 1, best_edge = nan;  // best_edge: the stop te if the winner is an edge
  bool found = false;
  const auto take = [&](double q, double d, double edge) SPINDOWN_LANE_BODY {
    if (q * best_d > best_q * d) best_q = q, best_d = d, best = sums, best_edge = edge, found = true;
  };
  // The candidates with m moving samples, given their sums. Inlined (as take) into the scan, so
  // that the running sums stay in registers.
  const auto weigh = [&](std::size_t m) SPINDOWN_LANE_BODY {
    const double t = tau[m - 1];
    // The plain line over the first m counts if it falls (U, B > 0) and stops in (τ[m−1], τ[m]].
    const double det = sums.det(), U = sums.u(), B = sums.b();
    if (det > 0 && U > 0 && B > 0 && U > B * t && (m == n || U <= B * tau[m])) take(sums.plain_gain_times_det(), det, nan);
    // The edge: stopped exactly at the next sample.
    if (m < n) {
      const double num = sums.edge_num(tau[m]), den = sums.edge_den(tau[m]);
      if (den > 0 && num > 0) take(num * num, den, tau[m]);
    }
  };
  // The bound from the candidates at the hint; they are weighed again in the scan.
  std::size_t first = 3;
  double bound = 0;
  // The hint's lanes, for the scan's start (never past the hint); written before read, not zeroed.
  std::unique_ptr<double[]> checkpoints;
  if (hint >= 3 && hint <= n) {
    checkpoints = std::make_unique_for_overwrite<double[]>((hint + checkpoint_every - 1) / checkpoint_every * checkpoint_size);
    sums = line_sums_with_checkpoints(tau, w, wy, hint, checkpoints.get());
    weigh(hint);
    if (found) {
      // The first count with P(m) ≥ G (P is monotone: a suffix sum of non-negative terms).
      bound = best_q / best_d * (1 - 1e-9);
      const double total = eval.weighted_sum_sq();
      for (std::size_t hi = hint; first < hi;) {
        const std::size_t mid = first + (hi - first) / 2;
        if (total - eval.weighted_sum_sq_from(mid) < bound) first = mid + 1;
        else hi = mid;
      }
    }
    sums = LineSums{}, best = LineSums{}, best_q = 0, best_d = 1, best_edge = nan, found = false;
  }
  const auto scan_from = [&](std::size_t from) {
    sums = checkpoints ? line_sums_from_checkpoint(tau, w, wy, from - 1, checkpoints.get())
                       : line_sums(tau, w, wy, 0, from - 1);
    for (std::size_t m = from; m <= n; ++m) {
      sums.add(w[m - 1], wy[m - 1], tau[m - 1]);
      weigh(m);
    }
  };
  scan_from(first);
  // The bound holds if the scan's own best reaches G; a boundary test that the hint's sums and
  // the scan's round differently could deny it that candidate: then every count is weighed.
  if (first > 3 && !(found && best_q / best_d >= bound)) {
    sums = LineSums{}, best = LineSums{}, best_q = 0, best_d = 1, best_edge = nan, found = false;
    scan_from(3);
  }
  if (!found) return std::nullopt;
  return std::isnan(best_edge) ? best.plain() : best.edge(best_edge);
}

}  // namespace spindown::friction
