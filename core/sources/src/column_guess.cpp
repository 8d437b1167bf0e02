#include "spindown/column_guess.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <utility>
#include <vector>

namespace spindown {

namespace {

std::vector<double> finite_values(const std::vector<double>& column) {
  std::vector<double> v;
  v.reserve(column.size());
  for (double x : column)
    if (std::isfinite(x)) v.push_back(x);
  return v;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

struct TimeCandidate {
  int column = -1;
  bool counter = false;  // 0, 1, 2… by exactly 1: a sample number
  double first = 0, last = 0, step = 0;
  TimeUnit unit = TimeUnit::s;
};

// Rises steadily: at least 95 % of the steps forward, their median positive, and nine in ten
// of them within 5x the median (a clock, not a reading that happens to grow).
std::optional<TimeCandidate> as_time(const std::vector<double>& v, int column) {
  if (v.size() < 5) return std::nullopt;
  std::vector<double> steps;
  steps.reserve(v.size());
  std::size_t forward = 0;
  for (std::size_t i = 1; i < v.size(); ++i) {
    const double d = v[i] - v[i - 1];
    forward += d > 0;
    if (d > 0) steps.push_back(d);
  }
  if (forward * 20 < (v.size() - 1) * 19) return std::nullopt;
  const double step = median(steps);
  if (!(step > 0)) return std::nullopt;
  const std::size_t steady = static_cast<std::size_t>(
      std::count_if(steps.begin(), steps.end(), [&](double d) { return d <= 5 * step; }));
  if (steady * 10 < steps.size() * 9) return std::nullopt;
  TimeCandidate c;
  c.column = column;
  c.first = v.front();
  c.last = *std::max_element(v.begin(), v.end());  // (a last line cut short is no end)
  c.step = step;
  c.unit = time_unit_from_values(v);
  c.counter = step == 1 && (v.front() == 0 || v.front() == 1) &&
              std::all_of(v.begin(), v.end(), [](double x) { return x == std::floor(x); });
  return c;
}

struct ValueCandidate {
  int column = -1;
  double roughness = 0;  // median |second difference| over the range: small for a coast
  std::string why;
  double peak = 0;
  bool partial = false;  // a fall under way that neither starts at a peak nor ends at rest
};

// Rises and falls, or falls to a rest, over at least 5 samples from 90 % to 10 % of its drop, and
// smoothly.
std::optional<ValueCandidate> as_value(const std::vector<double>& v, int column) {
  if (v.size() < 10) return std::nullopt;
  const auto [lo_it, hi_it] = std::minmax_element(v.begin(), v.end());
  const double lo = *lo_it, hi = *hi_it, range = hi - lo;
  if (!(range > 0)) return std::nullopt;
  const std::size_t peak = static_cast<std::size_t>(hi_it - v.begin());
  const double start = v.front(), end = v.back();
  const bool rises_and_falls = peak > 0 && hi - start >= 0.3 * range && hi - end >= 0.3 * range;
  // At rest at the end: its last 5 % (at least 3 samples) within 5 % of the range of its lowest.
  const std::size_t tail = std::max<std::size_t>(3, v.size() / 20);
  const bool rests = std::all_of(v.end() - static_cast<std::ptrdiff_t>(tail), v.end(),
                                 [&](double x) { return x - lo <= 0.05 * range; });
  // (and a rest is near zero: a fall from 436 that ends at 420 is a coast under way, not at rest)
  const bool falls_to_rest = rests && hi - end >= 0.5 * range && std::abs(end) <= 0.2 * std::abs(hi);
  // A coast under way (a recording started and stopped mid-coast): its level at the end (median of
  // the last tenth) at least 1 % below its level at the start and far more than the reading's
  // sample-to-sample jitter.
  bool falls_steadily = false;
  if (!rises_and_falls && !falls_to_rest) {
    const std::size_t k = std::max<std::size_t>(3, v.size() / 10);
    const double a = median(std::vector<double>(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k)));
    const double b = median(std::vector<double>(v.end() - static_cast<std::ptrdiff_t>(k), v.end()));
    std::vector<double> jitter;
    jitter.reserve(v.size());
    for (std::size_t i = 1; i < v.size(); ++i) jitter.push_back(std::abs(v[i] - v[i - 1]));
    falls_steadily = a - b >= 0.01 * std::abs(a) && a - b > 20 * median(std::move(jitter));
  }
  if (!rises_and_falls && !falls_to_rest && !falls_steadily) return std::nullopt;
  // How long the fall after the peak takes from 90 % to 10 % of the way down.
  std::size_t at90 = peak, at10 = peak;
  while (at90 < v.size() && v[at90] > end + 0.9 * (hi - end)) ++at90;
  at10 = at90;
  while (at10 < v.size() && v[at10] > end + 0.1 * (hi - end)) ++at10;
  if (at10 - at90 < 5) return std::nullopt;
  // Smoothly: no fall of more than a tenth of the range from one sample to the next (a current
  // that stops at the cut, a relay). A fall under way, a few per cent of its level, may lose a
  // good part of that over a logger's pause of a second or two: half of it there.
  const double largest_drop = falls_steadily ? 0.5 * range : 0.1 * range;
  for (std::size_t i = 1; i < v.size(); ++i)
    if (v[i - 1] - v[i] > largest_drop) return std::nullopt;
  std::vector<double> curvature;
  curvature.reserve(v.size());
  for (std::size_t i = 1; i + 1 < v.size(); ++i) curvature.push_back(std::abs(v[i + 1] - 2 * v[i] + v[i - 1]));
  ValueCandidate c;
  c.column = column;
  c.roughness = median(curvature) / range;
  c.peak = hi;
  c.partial = falls_steadily;
  c.why = rises_and_falls ? fmt::format("rises to {:g} and falls to {:g} over {} samples", hi, end, at10 - peak)
          : falls_to_rest ? fmt::format("falls from {:g} to a rest at {:g} over {} samples", hi, end, at10 - peak)
                          : fmt::format("falls steadily from {:g} to {:g} over {} samples (a coast under way)", start,
                                        end, v.size());
  return c;
}

std::string_view unit_words(TimeUnit u) {
  switch (u) {
    case TimeUnit::s: return "seconds";
    case TimeUnit::ms: return "milliseconds, as millis() counts";
    case TimeUnit::us: return "microseconds, as micros() counts";
  }
  return "";
}

}  // namespace

TimeUnit time_unit_from_values(std::span<const double> t, bool* integral_out, double* step_out) {
  std::vector<double> steps;
  bool integral = true;
  for (std::size_t i = 0; i < t.size() && i < 65; ++i) {
    integral = integral && t[i] == std::floor(t[i]);
    if (i > 0 && t[i] > t[i - 1]) steps.push_back(t[i] - t[i - 1]);
  }
  const double step = median(std::move(steps));
  if (integral_out) *integral_out = integral;
  if (step_out) *step_out = step;
  return integral && step >= 1 ? (step >= 5000 ? TimeUnit::us : TimeUnit::ms) : TimeUnit::s;
}

ColumnGuess guess_columns(const std::vector<std::vector<double>>& columns) {
  ColumnGuess g;
  std::vector<TimeCandidate> times;
  std::vector<std::vector<double>> finite;
  finite.reserve(columns.size());
  for (std::size_t c = 0; c < columns.size(); ++c) {
    finite.push_back(finite_values(columns[c]));
    if (auto t = as_time(finite.back(), static_cast<int>(c))) times.push_back(*t);
  }
  // A sample number gives way to a clock.
  if (times.size() > 1)
    times.erase(std::remove_if(times.begin(), times.end(), [](const TimeCandidate& t) { return t.counter; }),
                times.end());
  if (!times.empty()) {
    const TimeCandidate& t = times.front();
    g.time = t.column;
    g.time_unit = t.unit;
    g.time_counter = t.counter;
    g.time_why = fmt::format("rises steadily from {:g} to {:g} in steps of {:g} ({})", t.first, t.last, t.step,
                             unit_words(t.unit));
  }
  std::optional<ValueCandidate> best;
  for (std::size_t c = 0; c < columns.size(); ++c) {
    if (static_cast<int>(c) == g.time) continue;
    if (std::any_of(times.begin(), times.end(), [&](const TimeCandidate& t) { return t.column == int(c); })) continue;
    auto v = as_value(finite[c], static_cast<int>(c));
    // A whole coast before a fall under way; the smoother of two alike.
    if (v && (!best || std::pair(v->partial, v->roughness) < std::pair(best->partial, best->roughness)))
      best = std::move(v);
  }
  if (best) {
    g.value = best->column;
    g.value_why = best->why;
    g.value_peak = best->peak;
  }
  return g;
}

std::optional<std::string> column_proposal(const ColumnGuess& g) {
  if (g.time < 0) return std::nullopt;
  if (g.time_counter) {  // 0, 1, 2…: the samples' numbers; taken for ms they would make every rate wrong
    if (g.value < 0) return std::nullopt;
    return fmt::format("column {} counts the samples 0, 1, 2 … (a sample number, not a clock) and column {} {}: give "
                       "the time between samples, e.g. --period-ms 20 for the lab sketch's delay(20) or a scope's "
                       "Increment in ms, with --value-column {}",
                       g.time + 1, g.value + 1, g.value_why, g.value + 1);
  }
  if (g.value < 0)
    return fmt::format("column {} {}: try --time-column {} --time-unit {} and name the speed (or back-EMF) column "
                       "with --value-column (no column falls as a coast does)",
                       g.time + 1, g.time_why, g.time + 1, time_unit_name(g.time_unit));
  std::string s = fmt::format("column {} {} and column {} {}: try --time-column {} --time-unit {} --value-column {}",
                              g.time + 1, g.time_why, g.value + 1, g.value_why, g.time + 1, time_unit_name(g.time_unit),
                              g.value + 1);
  // Readings up to tens of thousands are a speed, or a back-EMF printed in whole millivolts (a sketch
  // avoiding floats: analogRead(A0) * 5000L / 1023): both are said, the user knows which.
  if (g.value_peak > 30)
    s += fmt::format(" --value-unit rpm (readings up to {:g} are no back-EMF in volts; --value-unit rad/s if they "
                     "are rad/s{})",
                     g.value_peak, g.value_peak <= 50000 ? ", --value-unit mV if they are millivolts" : "");
  return s;
}

}  // namespace spindown
