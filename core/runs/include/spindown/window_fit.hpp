#pragma once
// A least-squares line over a window of a SampleStore's samples, its sums kept so that a sample
// can join or leave in O(1): what run finding's windows (the hold window, a cut's lead-in, a
// coast's last second) are measured with. The sums are kept in pairs of lanes, (Σt, Σv) and
// (Σt², Σv²): each lane does the scalar operation, so every sum has the bits it would have alone,
// and two sums take one instruction.
#include <algorithm>
#include <cmath>
#include <cstddef>

#include "spindown/sample_store.hpp"

namespace spindown {

struct WindowFit {
  using Pair = double __attribute__((vector_size(2 * sizeof(double))));
  double span_s = 1.0;
  std::size_t first = 0, end = 0;  // absolute indices [first, end)
  double t0 = 0;                   // time origin for the sums (precision)
  double n = 0;
  Pair s1{}, s2{};  // (Σt, Σv), (Σt², Σv²), t from t0
  double stv = 0;   // Σt·v
  unsigned updates = 0;
  double st() const { return s1[0]; }
  double sv() const { return s1[1]; }
  double stt() const { return s2[0]; }
  double svv() const { return s2[1]; }
  void clear(std::size_t at, double t_origin);
  void add(double t, double v) {
    const Pair d{t - t0, v};
    n += 1, s1 += d, s2 += d * d, stv += d[0] * d[1];
    ++updates;
  }
  void remove(double t, double v) {
    const Pair d{t - t0, v};
    n -= 1, s1 -= d, s2 -= d * d, stv -= d[0] * d[1];
    ++updates;
  }
  // add(t_in, v_in) then remove(t_out, v_out), bit for bit, in one pass over the sums.
  void slide(double t_in, double v_in, double t_out, double v_out) {
    const Pair in{t_in - t0, v_in}, out{t_out - t0, v_out};
    s1 = s1 + in - out;
    s2 = s2 + in * in - out * out;
    stv = stv + in[0] * in[1] - out[0] * out[1];
    updates += 2;
  }
  double mean() const { return n > 0 ? sv() / n : 0.0; }
  double sxx() const { return stt() - st() * st() / n; }
  double slope() const {
    if (n < 2) return 0.0;
    const double sxx_ = sxx();
    if (!(sxx_ > 0)) return 0.0;
    return (stv - st() * sv() / n) / sxx_;
  }
  double slope_se() const { return sxx() > 0 ? resid_sd() / std::sqrt(sxx()) : 0.0; }
  double resid_sd() const {
    if (n < 3) return 0.0;
    const double syy = svv() - sv() * sv() / n;
    const double sxy = stv - st() * sv() / n;
    const double sxx_ = sxx();
    const double sse = sxx_ > 0 ? syy - sxy * sxy / sxx_ : syy;
    return std::sqrt(std::max(sse, 0.0) / (n - 2));
  }
};

// The window of span `span` (s) over samples [from, to), its sums added afresh (ring and mask:
// SampleStore::data() and mask(), for a loop that keeps them in locals).
WindowFit window_over(const SampleStore::Sample* ring, std::size_t mask, double span, std::size_t from, std::size_t to);
inline WindowFit window_over(const SampleStore& s, double span, std::size_t from, std::size_t to) {
  return window_over(s.data(), s.mask(), span, from, to);
}

}  // namespace spindown
