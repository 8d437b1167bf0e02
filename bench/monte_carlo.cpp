// monte_carlo: the accuracy study of issue 6. Generates RUNS runs of one bench and one friction
// truth at the lab's noise and quantization (white noise, 1 % commutator ripple, 10-bit ADC on
// 5 V, 2-decimal printing, 20 ms loop with jitter), fits each one as `spindown fit` does (read
// the printed text, find the run, fit the three models; the combined model's c3 and c4 are
// kept), and computes the Cramér–Rao bound for the same sampling and noise.
//
// Writes into OUT_DIR: the runs as printed (runNNNNN.txt) and index.tsv (for SciPy, with the
// cut and the stop given for free), spindown.tsv (c3, c4 and their standard errors per run) and
// crb.json (truth, effective noise, the bound). bench/monte_carlo.sh runs SciPy on the same
// files and prints the comparison.
//
// The bound: parameters θ = (u0, a = c3/J, d = K_b·c4/J) of the reading u(τ) = (u0 + d/a)e^(−aτ)
// − d/a (0 after the stop), with the cut time and the zero level known (a bound for estimators
// that must find them too). Fisher information F = Σ ∇u ∇uᵀ / σ² over each run's own sample
// times, averaged over runs. Quantization is treated as additive noise, measured rather than
// assumed: the error e = printed reading − true reading over the coasts holds white noise, the
// ADC step, the printing step (≈ σ_w² + Δ_adc²/12 + Δ_print²/12 when the noise dithers them) and
// the commutator ripple, whose variance grows with the reading (ripple·u)²/2. So σ² is taken as
// a function of the true reading, σ²(u) = α + β·u², by least squares of e² on u² over all runs,
// and F = Σ ∇u ∇uᵀ / σ²(u). (The bound with one constant σ² = mean e² is reported beside it:
// looser where the ripple is small, tighter where it is large.)
//
// usage: monte_carlo OUT_DIR [RUNS=500] [SEED=1] [TRUTH_JSON] [ADC_BITS=10] [DECIMALS=2]
//   TRUTH_JSON: a data/*.truth.json (c_v, c_c, e0, noise_v, ripple); default the lab's 3 V run.
//   ADC_BITS 0 and DECIMALS −1 (printed to 6) take the quantization out, to see what it costs.
#include <Eigen/Dense>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "spindown/arduino_text.hpp"
#include "spindown/fit.hpp"
#include "spindown/runs.hpp"
#include "spindown/synthetic_run.hpp"

namespace {

using namespace spindown;

struct Truth {
  double c_v = 1.822e-7, c_c = 1.1389e-4, e0 = 2.8, noise_v = 0.004, ripple = 0.01;
};

// The true reading (V) τ seconds after the cut, and its gradient in (u0, a, d).
struct Model {
  double u0, a, d;
  double value(double tau) const {
    const double u = (u0 + d / a) * std::exp(-a * tau) - d / a;
    return u > 0 ? u : 0.0;
  }
  Eigen::Vector3d gradient(double tau) const {
    const double e = std::exp(-a * tau);
    if ((u0 + d / a) * e - d / a <= 0) return Eigen::Vector3d::Zero();  // stopped: flat
    return {e, -(d / (a * a)) * e - tau * (u0 + d / a) * e + d / (a * a), (e - 1) / a};
  }
};

// The command line: OUT_DIR [RUNS] [SEED] [TRUTH_JSON] [ADC_BITS] [DECIMALS].
struct Args {
  std::filesystem::path dir;
  long runs = 500, seed = 1, adc_bits = 10, decimals = 2;
  Truth truth;
};

// The arguments, or the exit code 2 with why on stderr.
std::optional<Args> parse_args(int argc, char** argv) {
  if (argc < 2 || argc > 7) {
    std::cerr << "usage: monte_carlo OUT_DIR [RUNS=500] [SEED=1] [TRUTH_JSON] [ADC_BITS=10] [DECIMALS=2]\n";
    return std::nullopt;
  }
  Args a;
  a.dir = argv[1];
  a.runs = argc > 2 ? std::strtol(argv[2], nullptr, 10) : 500;
  a.seed = argc > 3 ? std::strtol(argv[3], nullptr, 10) : 1;
  a.adc_bits = argc > 5 ? std::strtol(argv[5], nullptr, 10) : 10;
  a.decimals = argc > 6 ? std::strtol(argv[6], nullptr, 10) : 2;
  if (a.runs < 2 || a.runs > 100'000 || a.seed < 0 || a.adc_bits < 0 || a.adc_bits > 16 || a.decimals < -1 ||
      a.decimals > 6) {
    std::cerr << "monte_carlo: RUNS must be 2…100000, SEED ≥ 0, ADC_BITS 0…16, DECIMALS −1…6\n";
    return std::nullopt;
  }
  if (argc > 4) {
    std::ifstream f(argv[4]);
    try {
      const auto j = nlohmann::json::parse(f);
      a.truth.c_v = j.at("c_v");
      a.truth.c_c = j.at("c_c");
      a.truth.e0 = j.contains("runs") ? j.at("runs").at(0).at("e0") : j.at("e0");
      a.truth.noise_v = j.value("noise_v", a.truth.noise_v);
      a.truth.ripple = j.value("ripple", a.truth.ripple);
    } catch (const std::exception& e) {
      std::cerr << fmt::format("monte_carlo: {}: not a truth file with c_v, c_c, e0 ({})\n", argv[4], e.what());
      return std::nullopt;
    }
  }
  return a;
}

// The reading's error e = printed − true over the coasts: its mean square (the constant σ²), and
// the sums of a straight-line fit e² = α + β·u² (σ² as a function of the true reading u).
struct ReadingError {
  double sq_resid = 0;
  long n = 0;
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  void add(double u, double r) {
    sq_resid += r * r;
    ++n;
    sx += u * u;
    sy += r * r;
    sxx += u * u * u * u;
    sxy += u * u * r * r;
  }
  double sigma2() const { return sq_resid / double(n); }
  double beta() const {
    const double nr = double(n);
    return (nr * sxy - sx * sy) / (nr * sxx - sx * sx);
  }
  double alpha() const { return (sy - beta() * sx) / double(n); }
};

// The bound's standard deviations of c3 and c4, for σ²(u) = α + β·u² and for constant σ².
struct Bound {
  double sd_c3 = 0, sd_c4 = 0, flat_sd_c3 = 0, flat_sd_c4 = 0;
};

// The bound's variances of c3, c4 averaged over runs, each run's Fisher information over its own
// sample times (τ after the cut).
Bound cramer_rao_bound(const std::vector<std::vector<double>>& taus_per_run, const Model& model,
                       const ReadingError& error, double J, double kb) {
  const double sigma2 = error.sigma2(), alpha = error.alpha(), beta = error.beta();
  double crb_var3 = 0, crb_var4 = 0, flat_var3 = 0, flat_var4 = 0;
  for (const auto& taus : taus_per_run) {
    Eigen::Matrix3d F = Eigen::Matrix3d::Zero(), F_flat = Eigen::Matrix3d::Zero();
    for (double tau : taus) {
      const Eigen::Vector3d g = model.gradient(tau);
      const double u = model.value(tau);
      F += g * g.transpose() / std::max(alpha + beta * u * u, 1e-12);
      F_flat += g * g.transpose() / sigma2;
    }
    const Eigen::Matrix3d cov = F.inverse(), cov_flat = F_flat.inverse();
    crb_var3 += J * J * cov(1, 1);
    crb_var4 += (J / kb) * (J / kb) * cov(2, 2);
    flat_var3 += J * J * cov_flat(1, 1);
    flat_var4 += (J / kb) * (J / kb) * cov_flat(2, 2);
  }
  const double nruns = double(taus_per_run.size());
  return {std::sqrt(crb_var3 / nruns), std::sqrt(crb_var4 / nruns), std::sqrt(flat_var3 / nruns),
          std::sqrt(flat_var4 / nruns)};
}

// The study: each run generated, printed, measured against the truth and fitted; then the bound.
class Study {
 public:
  explicit Study(const Args& a)
      : a_(a),
        model_{a.truth.e0, a.truth.c_v / J_, kb_ * a.truth.c_c / J_},
        index_(a.dir / "index.tsv"),
        ours_(a.dir / "spindown.tsv"),
        plain_(a.dir / "spindown-unweighted.tsv") {
    index_ << "file\tt_cut_s\tt_stop_s\tJ\tKb\tc_v\tc_c\te0\tsamples\n";
    ours_ << "file\tc3\tc4\tse3\tse4\n";
    plain_ << "file\tc3\tc4\tse3\tse4\n";
    taus_per_run_.reserve(static_cast<std::size_t>(a.runs));
  }

  // Exit code: 0 when every run was fitted, else 1.
  int run() {
    for (long i = 0; i < a_.runs; ++i) study_run(i);
    const nlohmann::json out = results(cramer_rao_bound(taus_per_run_, model_, error_, J_, kb_));
    std::ofstream(a_.dir / "crb.json") << out.dump(2) << '\n';
    std::cout << out.dump(2) << '\n';
    return failed_ == 0 ? 0 : 1;
  }

 private:
  void study_run(long i) {
    const Truth& truth = a_.truth;
    SyntheticRunSpec spec;
    spec.friction = FrictionTerms{truth.c_v, truth.c_c};
    spec.e0_v = truth.e0;
    spec.noise_v = truth.noise_v;
    spec.ripple = truth.ripple;
    spec.lead_in_s = 1.0;
    spec.tail_s = 2.0;
    spec.seed = static_cast<std::uint64_t>(a_.seed * 1'000'003 + i);
    spec.adc_bits = static_cast<int>(a_.adc_bits);
    spec.decimals = static_cast<int>(a_.decimals);
    const SyntheticRun run = make_synthetic_run(spec);
    const std::string name = fmt::format("run{:05d}.txt", i + 1);
    const std::string text = to_arduino_text(run, a_.decimals < 0 ? 6 : static_cast<int>(a_.decimals), true);
    std::ofstream(a_.dir / name, std::ios::binary) << text;
    index_ << fmt::format("{}\t{:.6f}\t{:.6f}\t{:.9g}\t{:.9g}\t{:.9g}\t{:.9g}\t{:.4f}\t{}\n", name,
                          run.t_cut_ms / 1000.0, run.t_cut_ms / 1000.0 + run.t_stop_s, J_, kb_, truth.c_v, truth.c_c,
                          truth.e0, run.t_ms.size());
    measure_reading(run);
    fit_as_spindown(text, name);
  }

  // The bound's information over this run's sample times (printed millis are floored: +0.5 ms),
  // and the reading's error over its coast.
  void measure_reading(const SyntheticRun& run) {
    std::vector<double>& taus = taus_per_run_.emplace_back();
    for (std::size_t k = 0; k < run.t_ms.size(); ++k) {
      const double tau = (run.t_ms[k] + 0.5 - run.t_cut_ms) / 1000.0;
      if (tau < 0) continue;
      taus.push_back(tau);
      if (tau < run.t_stop_s) {
        const double u = model_.value(tau);
        error_.add(u, run.volts[k] - u);
      }
    }
  }

  // spindown, as `spindown fit` does it, and the same run by unweighted least squares.
  void fit_as_spindown(const std::string& text, const std::string& name) {
    const auto t0 = std::chrono::steady_clock::now();
    const Recording rec = read_arduino_text(text, name);
    const Segmentation seg = find_runs(rec);
    const FitOptions opt;
    const ModelFit* combined = nullptr;
    RunFit fit;
    if (seg.runs.size() == 1) {
      fit = fit_run(rec, seg.runs.front(), opt);
      combined = fit.model(ModelKind::combined);
    }
    fit_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const Parameter* c3 = combined ? combined->param("c3") : nullptr;
    const Parameter* c4 = combined ? combined->param("c4") : nullptr;
    if (!combined || !combined->converged || !c3 || !c4) {
      ++failed_;
      std::cerr << fmt::format("monte_carlo: {}: {} runs found, combined fit {}\n", name, seg.runs.size(),
                               combined ? combined->message : "missing");
      return;
    }
    ++fitted_;
    ours_ << fmt::format("{}\t{:.9g}\t{:.9g}\t{:.9g}\t{:.9g}\n", name, c3->value, c4->value, c3->std_error,
                         c4->std_error);
    // The same run by unweighted least squares (FitOptions::weighted = false), for comparison.
    FitOptions unweighted;
    unweighted.weighted = false;
    const RunFit plain_fit = fit_run(rec, seg.runs.front(), unweighted);
    if (const ModelFit* m = plain_fit.model(ModelKind::combined); m && m->converged) {
      const Parameter *p3 = m->param("c3"), *p4 = m->param("c4");
      plain_ << fmt::format("{}\t{:.9g}\t{:.9g}\t{:.9g}\t{:.9g}\n", name, p3->value, p4->value, p3->std_error,
                            p4->std_error);
    }
  }

  nlohmann::json results(const Bound& bound) const {
    const Truth& truth = a_.truth;
    const double adc_step = a_.adc_bits > 0 ? 5.0 / double(1L << a_.adc_bits) : 0.0;
    const double print_step = a_.decimals >= 0 ? std::pow(10.0, -double(a_.decimals)) : 0.0;
    const double alpha = error_.alpha();
    return {
        {"runs", a_.runs},
        {"fitted", fitted_},
        {"failed", failed_},
        {"c_v", truth.c_v},
        {"c_c", truth.c_c},
        {"e0", truth.e0},
        {"noise_v", truth.noise_v},
        {"ripple", truth.ripple},
        {"adc_bits", a_.adc_bits},
        {"decimals", a_.decimals},
        {"J", J_},
        {"Kb", kb_},
        {"sigma_eff_v", std::sqrt(error_.sigma2())},
        {"sigma_additive_model_v", std::sqrt(truth.noise_v * truth.noise_v + adc_step * adc_step / 12 +
                                             print_step * print_step / 12)},
        {"sigma2_alpha_v2", alpha},
        {"sigma2_beta", error_.beta()},
        {"sigma_at_zero_v", std::sqrt(std::max(alpha, 0.0))},
        {"crb_sd_c3", bound.sd_c3},
        {"crb_sd_c4", bound.sd_c4},
        {"crb_flat_sd_c3", bound.flat_sd_c3},
        {"crb_flat_sd_c4", bound.flat_sd_c4},
        {"spindown_fit_ms_per_run", 1e3 * fit_seconds_ / double(a_.runs)},
    };
  }

  const Args& a_;
  const BenchParams bench_;  // the lab's J and K_b
  const double J_ = bench_.inertia_kg_m2, kb_ = bench_.kb_v_s_per_rad;
  const Model model_;
  std::ofstream index_, ours_, plain_;
  ReadingError error_;
  std::vector<std::vector<double>> taus_per_run_;  // the bound needs σ²(u), known only at the end
  long fitted_ = 0, failed_ = 0;
  double fit_seconds_ = 0;
};

}  // namespace

int main(int argc, char** argv) {
  const std::optional<Args> args = parse_args(argc, argv);
  if (!args) return 2;
  std::error_code ec;
  std::filesystem::create_directories(args->dir, ec);
  if (ec) {
    std::cerr << fmt::format("monte_carlo: cannot create {}: {}\n", args->dir.string(), ec.message());
    return 1;
  }
  return Study(*args).run();
}
