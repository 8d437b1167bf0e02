#include "spindown/fit_checks.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <limits>

#include "fit_family.hpp"
#include "spindown/residual_bins.hpp"

namespace spindown {

namespace {

// The fit's best model (nullptr when none converged).
const ModelFit* best_model(const RunFit& fit) {
  const auto kind = parse_model(fit.best);
  return kind ? fit.model(*kind) : nullptr;
}

}  // namespace

double reading_step(std::span<const double> values) {
  // The smallest change between neighbouring readings is the step when the readings are quantized:
  // looked for where they change fastest (the first 512, from the cut); then (nearly) every reading
  // (every 8th tells as well as all) is a whole number of steps from the first. Cheap: it runs on
  // every fitted run.
  if (values.size() < 8) return 0;
  double step = INFINITY;
  const std::size_t head = std::min<std::size_t>(values.size(), 512);
  for (std::size_t i = 1; i < head; ++i) {
    const double d = std::fabs(values[i] - values[i - 1]);
    step = d > 0 && d < step ? d : step;
  }
  if (!(step > 0) || !std::isfinite(step)) return 0;
  const double per_step = 1.0 / step;
  std::size_t whole = 0, seen = 0;
  for (std::size_t i = 0; i < values.size(); i += 8, ++seen) {
    const double k = (values[i] - values[0]) * per_step;  // any double (a reading of 1e300, NaN)
    whole += std::fabs(k - std::floor(k + 0.5)) < 0.05;
  }
  return whole * 10 >= seen * 9 ? step : 0.0;
}

std::vector<std::string> unit_doubts(const RunFit& fit, double peak, bool whole_numbers) {
  std::vector<std::string> out;
  const ModelFit* best = best_model(fit);
  const double omega0 = best ? best->omega0 : std::numeric_limits<double>::quiet_NaN();
  const double rpm_per_volt = 60.0 / (2 * M_PI) / fit.bench.kb_v_s_per_rad;
  switch (fit.quantity) {
    case Quantity::back_emf_volts:
      if (peak > plausible_max_volts) {
        const bool looks_rpm = std::fabs(peak / rpm_per_volt) <= 12.0;
        // Whole numbers within a 10-bit converter's range: the sketch printed analogRead()'s counts
        // (its "* 5.0 / 1023" line left out), the likelier reading on a lab bench than a slow motor in rpm.
        const bool counts = whole_numbers && peak <= 1023;
        // Whole numbers up to tens of thousands may as well be whole millivolts (a sketch avoiding
        // floats: analogRead(A0) * 5000L / 1023): both are said, the user knows which.
        const std::string mv = whole_numbers && peak <= 50000 ? ", or --value-unit mV if they are millivolts" : "";
        const std::string rpm = fmt::format("a speed in rpm ({:.3g} V at {:.0f} rpm/V): try --value-unit rpm{}",
                                            peak / rpm_per_volt, rpm_per_volt, mv);
        out.push_back(fmt::format(
            "readings up to {:.6g} V: far beyond any back-EMF a lab bench makes or an Arduino pin reads (0–5 V){} — "
            "the numbers below are not the motor's friction",
            peak,
            counts      ? fmt::format("; whole numbers up to {:g}: raw analogRead() counts of a 10-bit converter "
                                      "(the sketch's * 5.0 / 1023 left out): try --value-unit counts (x 5/1023 V)",
                                      peak)
            : looks_rpm ? "; they look like " + rpm
                        : std::string("; check the value's unit (--value-unit V, mV, rpm or rad/s)")));
        return out;
      }
      break;
    case Quantity::rpm:
      if (peak < 20.0 && peak > 0) {
        out.push_back(fmt::format("readings of at most {:.3g} rpm: a motor that barely turns, or volts read as rpm "
                                  "— try --value-unit V",
                                  peak));
        return out;
      }
      break;
    case Quantity::rad_per_s:
      break;
  }
  // Said with what the readings were taken as: a speed in km/h or m/s read as volts by default
  // (a file that names no unit) is found here, and the reader must see it was taken as volts.
  if (std::isfinite(omega0) && omega0 > plausible_max_omega)
    out.push_back(fmt::format(
        "a speed at the cut of {:.6g} rad/s ({:.0f} rpm): faster than a teaching flywheel turns — the readings were "
        "taken as {}{}; if that is not their unit, give it (--value-unit V, rpm or rad/s; a vehicle's km/h or m/s "
        "is not a shaft speed){}",
        omega0, omega0 * 60 / (2 * M_PI),
        fit.quantity == Quantity::back_emf_volts ? "back-EMF in volts"
        : fit.quantity == Quantity::rpm          ? "a speed in rpm"
                                                 : "a speed in rad/s",
        fit.quantity == Quantity::back_emf_volts
            ? fmt::format(" ({:.4g} V at the cut ÷ K_b {:.4g} V·s/rad)", omega0 * fit.bench.kb_v_s_per_rad,
                          fit.bench.kb_v_s_per_rad)
            : std::string(),
        fit.quantity == Quantity::back_emf_volts ? "; else check K_b" : ""));
  return out;
}

double largest_curve_difference(const ModelFit& a, const ModelFit& b, std::span<const double> tau, double k,
                                double enough) {
  // The curves are smooth: every 4th sample and the last find their largest gap to well within a
  // step; it stops as soon as the gap reaches `enough`.
  double most = 0;
  for (std::size_t i = 0; i < tau.size(); i = i + 4 < tau.size() || i + 1 == tau.size() ? i + 4 : tau.size() - 1) {
    most = std::max(most, std::fabs(k * (a.omega_at(tau[i]) - b.omega_at(tau[i]))));
    if (most >= enough) break;
  }
  return most;
}

namespace {

double median_in_place(std::vector<double>& v) {
  if (v.empty()) return 0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}



}  // namespace

ResidualStructure residual_structure(const ModelFit& m, std::span<const double> tau, std::span<const double> y,
                                     std::size_t moving, double k, double step, double sigma) {
  ResidualStructure out;
  const std::size_t n = std::min({moving, tau.size(), y.size()});
  // Bins follow the run's length: residual_bin samples on a long run, fewer on a short one so
  // that a coast of a few dozen readings still has 8 bins to judge.
  const std::size_t bin = std::clamp<std::size_t>(n / 8, min_residual_bin, residual_bin);
  if (n < 4 * bin) return out;
  std::vector<double> r(n);
  for (std::size_t i = 0; i < n; ++i) r[i] = y[i] - k * m.omega_at(tau[i]);
  // Without the run's reading noise: the noise of one reading from first differences of the
  // residual (the smooth misfit cancels in them).
  std::vector<double> d;
  if (!(sigma > 0)) {
    d.resize(n - 1);
    for (std::size_t i = 1; i < n; ++i) d[i - 1] = std::fabs(r[i] - r[i - 1]);
    sigma = 1.4826 * median_in_place(d) / std::sqrt(2.0);
  }
  if (!(sigma > 0)) {  // mostly equal readings (a fine step): the rms of the differences instead
    double ss = 0;
    for (std::size_t i = 1; i < n; ++i) ss += (r[i] - r[i - 1]) * (r[i] - r[i - 1]);
    sigma = std::sqrt(ss / (2.0 * static_cast<double>(n - 1)));
  }
  if (!(sigma > 0)) return out;
  const ResidualBins bins = bin_residuals(r, bin, sigma);
  // A bin mean's noise: the white value σ/√bin, or what the bins' own jumps show when the noise
  // is correlated (a drive's speed filter) — measured only with enough bins to measure it, so a
  // short run's gross misfit is not taken for noise. A slow reading sits on one printed step for
  // many samples: its rounding does not average out within a bin, so a bin's mean is known no
  // better than the step's own spread, step/√12.
  const double noise = bins.mean.size() >= honest_noise_bins ? bins.bin_se : sigma / std::sqrt(double(bin));
  const double se = std::hypot(noise, step / std::sqrt(12.0));
  out.sigma = sigma;
  out.bin = bin;
  out.bin_se = se;
  double worst = 0;
  for (std::size_t b = 0; b < bins.mean.size(); ++b) {
    const double z = bins.mean[b] / se;
    ++out.bins;
    out.beyond += std::fabs(z) > 4;
    out.chi2 += std::min(z * z, 16.0);  // one stretch (a cut placed a sample off) does not decide
    if (std::fabs(z) > worst) {
      worst = std::fabs(z);
      out.worst_tau_s = tau[std::min(n - 1, bins.first[b] + bin / 2)];
      out.worst_mean = bins.mean[b];
    }
  }
  if (out.bins) out.excess_z = (out.chi2 - double(out.bins)) / std::sqrt(2.0 * double(out.bins));
  return out;
}

void check_fit(RunFit& fit, std::span<const double> tau, std::span<const double> y, std::size_t moving,
               std::span<const double> raw, double k) {
  fit.reading_step = reading_step(raw);
  double peak = 0;
  bool whole_numbers = !raw.empty();
  for (std::size_t i = 0; i < raw.size(); ++i) {
    peak = std::max(peak, raw[i]);
    if (i % 8 == 0) whole_numbers = whole_numbers && raw[i] == std::round(raw[i]);
  }
  fit.doubts = unit_doubts(fit, peak, whole_numbers);

  // What the print can resolve: a model with more friction terms whose curve stays within half a
  // step of a simpler one's is not told apart from it by the readings, whatever ΔBIC says.
  const ModelFit* best = best_model(fit);
  if (best && fit.reading_step > 0) {
    const ModelFit* simpler = nullptr;
    double gap = 0;
    for (const auto& m : fit.models) {
      if (!m.converged || friction::family_of(m.kind).size() >= friction::family_of(best->kind).size()) continue;
      const double diff = largest_curve_difference(*best, m, tau, k, 0.5 * fit.reading_step);
      if (diff < 0.5 * fit.reading_step && (!simpler || m.bic < simpler->bic)) simpler = &m, gap = diff;
    }
    if (simpler) {
      const std::string unit(quantity_unit(fit.quantity));
      fit.best_reason = fmt::format(
          "{} kept: {} changes the curve by at most {:.2g} {}, under half the reading's step of {:.3g} {} — the "
          "readings cannot tell them apart (by BIC alone {} would win, ΔBIC {:.1f})",
          model_name(simpler->kind), model_name(best->kind), gap, unit, fit.reading_step, unit,
          model_name(best->kind), simpler->bic - best->bic);
      fit.best = std::string(model_name(simpler->kind));
      best = simpler;
    }
  }

  // What a sensor offset imitates: the combined model's dry friction ends its curve at −k·d/r
  // (decel over rate) below zero, an offset of the whole coast's tail. A term that acts like an
  // offset within a converter's own (±2 reading steps: the ATmega's ±2 LSB) or of no physical size
  // (under 0.2 % of the reading at the cut: the Coulomb torque is then under 0.2 % of the viscous
  // one there) is not told from a zero level a few mV off, however large ΔBIC grows with thousands
  // of samples: the simpler viscous model is kept, and the reason says the readings cannot tell.
  if (best && best->kind == ModelKind::combined && best->rate > 0) {
    const ModelFit* viscous = fit.model(ModelKind::viscous);
    const double offset = std::fabs(k * best->decel / best->rate);
    const double v0 = std::fabs(k * best->omega0);
    const double allowed = std::max(2.0 * fit.reading_step, offset_allowance_fraction * v0);
    if (viscous && viscous->converged && offset <= allowed) {
      const std::string unit(quantity_unit(fit.quantity));
      fit.best_reason = fmt::format(
          "viscous kept: the combined model's dry friction acts like an offset of {:.2g} {} at the coast's end, "
          "within what a sensor offset imitates (±{:.2g} {}: 2 reading steps or 0.2 % of the reading at the cut) — "
          "the readings cannot tell dry friction from a zero level that far off (by BIC alone combined would win, "
          "ΔBIC {:.1f})",
          offset, unit, allowed, unit, viscous->bic - best->bic);
      fit.best = std::string(model_name(ModelKind::viscous));
      best = viscous;
    }
  }

  // A best model that misses: its residuals, averaged bin by bin, stand further from zero than
  // the noise of a bin's mean allows, taken over the whole run (Σz², each bin's z² counted up to 16
  // so that a stretch or two at the cut cannot decide, against its χ² spread). Such a
  // misfit moves the fitted coefficients far beyond their stated errors (a bias of about
  // 5·√n·misfit/σ standard errors for a missing windage or Stribeck term), so it is said; a misfit
  // the bins cannot see together (a 0.001 % windage, a sensor filter's correlated noise) is not.
  if (best && fit.doubts.empty()) {
    const ResidualStructure rs = residual_structure(*best, tau, y, moving, k, fit.reading_step, fit.reading_noise);
    const std::string_view unit = quantity_unit(fit.quantity);
    if (rs.bins >= 8 && rs.excess_z > misfit_excess_z)
      fit.doubts.push_back(fmt::format(
          "the {} model misses: over {} stretches of {} samples its mean residuals stand further from zero than "
          "noise allows (Σz² {:.0f} with each stretch counted up to 4², noise alone {} ± {:.0f}; {} stretches beyond 4 standard errors of {:.2g} {}; "
          "worst {:.2g} {} at {:.1f} s after the cut) — a misfit this visible moves the coefficients beyond their "
          "± (those assume the model holds): friction the model lacks; run `spindown explain` on this file to name it",
          fit.best, rs.bins, rs.bin, rs.chi2, rs.bins, std::sqrt(2.0 * double(rs.bins)), rs.beyond, rs.bin_se, unit,
          rs.worst_mean, unit, rs.worst_tau_s));
  }
}

}  // namespace spindown
