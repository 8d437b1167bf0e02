#include "explain_residuals.hpp"

#include <algorithm>
#include <cmath>
#include <limits>


namespace spindown::explain_detail {

std::vector<double> residual_of(std::span<const double> y, const EffectFit& f) {
  std::vector<double> r(y.size());
  for (std::size_t i = 0; i < y.size(); ++i) r[i] = y[i] - f.simulated[i];
  return r;
}

double systematic_mass(const ResidualBins& b, double bin_se) {
  double s = 0;
  for (double m : b.mean) s += (m / bin_se) * (m / bin_se);
  return std::max(0.0, s - static_cast<double>(b.mean.size()));
}

bool mass_significant(double mass, std::size_t bins) { return mass > 3.0 * std::sqrt(2.0 * static_cast<double>(bins)); }

std::vector<double> measured_speed(std::span<const double> y, double zero_level, double k) {
  std::vector<double> out(y.size());
  for (std::size_t i = 0; i < y.size(); ++i) out[i] = (y[i] - zero_level) / k;
  return out;
}

std::vector<Disagreement> locate(const ResidualBins& b, double bin_se, double z_thr, std::span<const double> tau,
                                 std::span<const double> residual, const std::vector<double>& speed, double t_cut) {
  std::vector<Disagreement> out;
  const std::size_t nb = b.mean.size();
  std::size_t k = 0;
  while (k < nb) {
    const double z = b.mean[k] / bin_se;
    if (std::abs(z) <= z_thr) {
      ++k;
      continue;
    }
    std::size_t e = k + 1;
    while (e < nb && std::abs(b.mean[e] / bin_se) > z_thr && (b.mean[e] > 0) == (z > 0)) ++e;
    const std::size_t i0 = b.first[k];
    const std::size_t i1 = e < nb ? b.first[e] : tau.size();  // one past the last sample
    Disagreement d;
    d.tau_from_s = tau[i0];
    d.tau_to_s = tau[i1 - 1];
    d.t_from_s = d.tau_from_s + t_cut;
    d.t_to_s = d.tau_to_s + t_cut;
    // The measured speed at the ends: a line through the end bin's readings, at the end's time (not
    // the model's speed: where the model misses, its speed is not where the coast was).
    const auto speed_at = [&](std::size_t from, std::size_t to, double at) {
      const double n = static_cast<double>(std::max<std::size_t>(to - from, 1));
      double st = 0, sv = 0;
      for (std::size_t i = from; i < to; ++i) st += tau[i], sv += speed[i];
      const double tm = st / n, vm = sv / n;
      double stt = 0, stv = 0;
      for (std::size_t i = from; i < to; ++i) stt += (tau[i] - tm) * (tau[i] - tm), stv += (tau[i] - tm) * (speed[i] - vm);
      return stt > 0 ? vm + stv / stt * (at - tm) : vm;
    };
    d.omega_from = speed_at(i0, e > k + 1 ? b.first[k + 1] : i1, d.tau_from_s);
    d.omega_to = speed_at(b.first[e - 1], i1, d.tau_to_s);
    double sum = 0;
    for (std::size_t i = i0; i < i1; ++i) sum += residual[i];
    d.mean_residual = sum / static_cast<double>(i1 - i0);
    for (std::size_t j = k; j < e; ++j)
      if (std::abs(b.mean[j]) > std::abs(d.peak_residual)) d.peak_residual = b.mean[j];
    d.z = d.peak_residual / bin_se;
    out.push_back(d);
    k = e;
  }
  // Keep the few that carry most of the disagreement, in time order.
  constexpr std::size_t keep = 6;
  if (out.size() > keep) {
    auto weight = [](const Disagreement& d) { return std::abs(d.mean_residual) * (d.tau_to_s - d.tau_from_s + 1e-3); };
    std::vector<Disagreement> sorted = out;
    std::sort(sorted.begin(), sorted.end(), [&](const auto& a, const auto& c) { return weight(a) > weight(c); });
    sorted.resize(keep);
    std::sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& c) { return a.tau_from_s < c.tau_from_s; });
    out = sorted;
  }
  return out;
}

double reading_quantum(std::span<const double> y) {
  std::vector<double> v(y.begin(), y.end());
  std::sort(v.begin(), v.end());
  double q = std::numeric_limits<double>::infinity();
  for (std::size_t i = 1; i < v.size(); ++i) {
    const double d = v[i] - v[i - 1];
    if (d > 1e-9 * (std::abs(v[i]) + 1e-12)) q = std::min(q, d);
  }
  return std::isfinite(q) ? q : 0.0;
}

double largest_change(const EffectFit& a, const EffectFit& b, std::size_t m) {
  double worst = 0;
  for (std::size_t i = 0; i < a.simulated.size(); i += m) {
    const std::size_t e = std::min(i + m, a.simulated.size());
    double s = 0;
    for (std::size_t j = i; j < e; ++j) s += b.simulated[j] - a.simulated[j];
    worst = std::max(worst, std::abs(s) / static_cast<double>(e - i));
  }
  return worst;
}

RoundingFree evidence_beyond_rounding(std::span<const double> y, std::span<const double> weight, const EffectFit& a,
                                      const EffectFit& b, std::size_t m, double q, double sigma) {
  RoundingFree out;
  const std::size_t n = std::min({a.simulated.size(), b.simulated.size(), y.size()});
  if (!(sigma > 0)) return out;
  // Σw, Σw·r and Σw·r² of each model's residual over the bins where rounding is noise.
  double sw = 0, sa = 0, sb = 0, saa = 0, sbb = 0;
  for (std::size_t i = 0; i < n; i += m) {
    const std::size_t e = std::min(i + m, n);
    std::size_t stepping = 0;  // samples that moved a step or more from the one before
    for (std::size_t j = i + 1; j < e; ++j) stepping += std::abs(y[j] - y[j - 1]) >= q * (1 - 1e-9);
    if (2 * stepping < e - i) continue;  // dwells: rounding's error there is deterministic
    for (std::size_t j = i; j < e; ++j) {
      const double w = j < weight.size() ? weight[j] : 1.0;
      const double ra = y[j] - a.simulated[j], rb = y[j] - b.simulated[j];
      sw += w, sa += w * ra, sb += w * rb, saa += w * ra * ra, sbb += w * rb * rb;
    }
    out.samples += e - i;
  }
  if (!(sw > 0)) return out;
  // A converter that truncates reads up to a step low while it dithers: a shift of each
  // residual, up to half a step, is the converter's, not the model's.
  const auto left = [&](double s, double ss) {
    const double shift = std::clamp(s / sw, -0.5 * q, 0.5 * q);
    return ss - 2 * shift * s + shift * shift * sw;
  };
  out.chi2_drop = (left(sa, saa) - left(sb, sbb)) / (sigma * sigma);
  return out;
}

bool contains(const std::vector<const Effect*>& v, const Effect* e) {
  return std::find(v.begin(), v.end(), e) != v.end();
}

std::vector<const Effect*> with_effect(const std::vector<const Effect*>& model, const Effect* e) {
  std::vector<const Effect*> out;
  for (const Effect& lib : effect_library())
    if (&lib == e || contains(model, &lib)) out.push_back(&lib);
  return out;
}

}  // namespace spindown::explain_detail
