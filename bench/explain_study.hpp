#pragma once
// Generated runs with a hidden effect, for the discrepancy workflow's study, benchmark and
// unit tests: families "none", "coulomb", "stribeck", "windage", "sensor_offset"; each draws
// a bench (J, K_b), loop period (10–50 ms), noise, ripple, lead-in kind and effect strength
// from a seed, and says which base model the workflow should start from.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "spindown/bench.hpp"
#include "spindown/effects.hpp"
#include "spindown/recording.hpp"
#include "spindown/synthetic_run.hpp"

namespace spindown::study {

inline const std::vector<std::string>& families() {
  static const std::vector<std::string> f{"none", "coulomb", "stribeck", "windage", "sensor_offset"};
  return f;
}

struct GeneratedRun {
  std::string family;            // the effect hidden from the base model ("none": nothing)
  std::string base;              // the base model to start from ("viscous" or "combined")
  std::vector<std::string> truth;  // effects in the truth (library names)
  SyntheticRunSpec spec;
  SyntheticRun run;
  Recording recording;
};

inline GeneratedRun generate(const std::string& family, std::uint64_t seed) {
  std::mt19937_64 rng(seed * 7919 + std::hash<std::string>{}(family));
  auto uni = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
  auto pick = [&](int n) { return static_cast<int>(std::uniform_int_distribution<int>(0, n - 1)(rng)); };
  GeneratedRun g;
  g.family = family;
  SyntheticRunSpec& s = g.spec;
  s.seed = seed + 1;
  // Bench: flywheel inertia ×0.5–2 of the lab's, motor speed constant 600–2000 rpm/V.
  s.bench.inertia_kg_m2 = 1.12687602e-5 * std::exp(uni(std::log(0.5), std::log(2.0)));
  s.bench.kb_v_s_per_rad = kb_from_speed_constant(uni(600, 2000));
  s.e0_v = uni(2.0, 3.6);
  s.period_s = uni(0.010, 0.050);
  s.jitter_s = uni(0.0, 0.001);
  s.noise_v = uni(0.001, 0.006);
  const double ripples[] = {0.0, 0.005, 0.01, 0.02};
  s.ripple = ripples[pick(4)];
  const LeadIn leads[] = {LeadIn::zeros, LeadIn::floating, LeadIn::supply};
  s.lead_in = leads[pick(3)];
  s.supply_v = s.e0_v + uni(0.1, 0.6);
  s.lead_in_s = uni(1.0, 4.0);
  s.tail_s = uni(2.0, 4.0);
  s.max_coast_s = 90;
  const double J = s.bench.inertia_kg_m2;
  const double w0 = s.e0_v / s.bench.kb_v_s_per_rad;
  // Combined friction: viscous rate α, Coulomb deceleration β for a 12–45 s coast.
  const double alpha = uni(0.005, 0.04);
  const double t_stop = uni(12, 45);
  const double beta = alpha * w0 / (std::exp(alpha * t_stop) - 1);
  FrictionTerms f;
  f.viscous = alpha * J;
  f.coulomb = beta * J;
  g.base = "combined";
  g.truth = {"viscous", "coulomb"};
  if (family == "none") {
    if (pick(3) == 0) {  // viscous only, base viscous (a run that coasts down exponentially)
      f.coulomb = 0;
      f.viscous = uni(0.05, 0.12) * J;
      s.max_coast_s = uni(30, 60);
      g.base = "viscous";
      g.truth = {"viscous"};
    }
  } else if (family == "coulomb") {
    g.base = "viscous";  // the lab's first belief
  } else if (family == "stribeck") {
    f.stribeck_static = f.coulomb * uni(1.6, 3.0);
    f.stribeck_speed = w0 * uni(0.06, 0.2);
    g.truth.push_back("stribeck");
  } else if (family == "windage") {
    f.windage = f.coulomb * uni(0.4, 1.5) / (w0 * w0);
    g.truth.push_back("windage");
  } else if (family == "sensor_offset") {
    s.offset_v = uni(0.03, 0.12);
    g.truth.push_back("sensor_offset");
  }
  s.friction = f;
  g.run = make_synthetic_run(s);
  g.recording.source = family + "-" + std::to_string(seed);
  g.recording.quantity = Quantity::back_emf_volts;
  for (std::size_t i = 0; i < g.run.t_ms.size(); ++i) g.recording.push(g.run.t_ms[i] / 1000.0, g.run.volts[i]);
  return g;
}

}  // namespace spindown::study
