#include "fit_start.hpp"

#include <cstring>

#include "vector_clones.hpp"

namespace spindown::friction {

// The eight sums are eight independent chains in sample order, kept side by side in vectors of
// four (the GCC/Clang vector extension: each lane is the scalar operation, so every build, of
// any vector width, gives the scalar loop's bits): Σ(∫, τ, y), Σ∫·(∫, τ, y) and Στ·(·, τ, y).
// Four samples at a time: their trapezoids in one vector operation, the running integral through
// them in order, then a 4×4 transpose turns the columns (∫, τ, y) into each sample's row.
SPINDOWN_VECTOR_CLONES IntegralForm integral_form(std::span<const double> tau, std::span<const double> y,
                                                  std::size_t moving) {
  using Four = double __attribute__((vector_size(4 * sizeof(double))));
  const auto load = [](Four& v, const double* p) { std::memcpy(&v, p, sizeof v); };  // no vector return: ABI
  Four plain = {}, by_integral = {}, by_time = {};
  const auto add = [&](double integral, double t, const Four& row) {  // row: (∫, τ, y, 0)
    plain += row, by_integral += integral * row, by_time += t * row;
  };
  double integral = 0;
  if (moving > 0) add(integral, tau[0], Four{integral, tau[0], y[0], 0.0});
  std::size_t i = 1;
  for (; i + 4 <= moving; i += 4) {
    Four t, v, t_before, y_before;
    load(t, &tau[i]), load(v, &y[i]), load(t_before, &tau[i - 1]), load(y_before, &y[i - 1]);
    const Four step = 0.5 * (v + y_before) * (t - t_before);
    const double i0 = integral + step[0], i1 = i0 + step[1], i2 = i1 + step[2], i3 = i2 + step[3];
    integral = i3;
    const Four in = {i0, i1, i2, i3}, zero = {};
    const Four even = __builtin_shufflevector(in, t, 0, 4, 2, 6), odd = __builtin_shufflevector(in, t, 1, 5, 3, 7);
    const Four even_y = __builtin_shufflevector(v, zero, 0, 4, 2, 6), odd_y = __builtin_shufflevector(v, zero, 1, 5, 3, 7);
    add(i0, t[0], __builtin_shufflevector(even, even_y, 0, 1, 4, 5));
    add(i1, t[1], __builtin_shufflevector(odd, odd_y, 0, 1, 4, 5));
    add(i2, t[2], __builtin_shufflevector(even, even_y, 2, 3, 6, 7));
    add(i3, t[3], __builtin_shufflevector(odd, odd_y, 2, 3, 6, 7));
  }
  for (; i < moving; ++i) {
    integral += 0.5 * (y[i] + y[i - 1]) * (tau[i] - tau[i - 1]);
    add(integral, tau[i], Four{integral, tau[i], y[i], 0.0});
  }
  const double s_i = plain[0], s_t = plain[1], s_y = plain[2], s_ii = by_integral[0], s_it = by_integral[1],
               s_iy = by_integral[2], s_tt = by_time[1], s_ty = by_time[2];
  IntegralForm out;  // columns (1, −∫r, −τ)
  out.ata << static_cast<double>(moving), -s_i, -s_t, -s_i, s_ii, s_it, -s_t, s_it, s_tt;
  out.atb << s_y, -s_iy, -s_ty;
  return out;
}

Theta integral_start(const Family& f, const IntegralForm& form) {
  const int p = f.size();
  int idx[3], j = 0;
  idx[j++] = 0;
  if (f.alpha_free) idx[j++] = 1;
  if (f.beta_free) idx[j++] = 2;
  Eigen::Matrix3d ata = Eigen::Matrix3d::Identity();
  Eigen::Vector3d atb = Eigen::Vector3d::Zero();
  for (int a = 0; a < p; ++a) {
    atb[a] = form.atb[idx[a]];
    for (int c = 0; c < p; ++c) ata(a, c) = form.ata(idx[a], idx[c]);
  }
  Theta th;
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(ata);
  if (ldlt.info() != Eigen::Success) return th;
  const Eigen::Vector3d sol = ldlt.solve(atb);
  if (!sol.allFinite()) return th;
  return unpack(f, sol.data());
}

}  // namespace spindown::friction
