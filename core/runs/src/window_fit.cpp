#include "spindown/window_fit.hpp"

namespace spindown {

void WindowFit::clear(std::size_t at, double t_origin) {
  first = end = at;
  t0 = t_origin;
  n = stv = 0;
  s1 = s2 = Pair{};
  updates = 0;
}

WindowFit window_over(const SampleStore::Sample* ring, std::size_t mask, double span, std::size_t from, std::size_t to) {
  WindowFit w;
  w.span_s = span;
  w.clear(from, from < to ? ring[from & mask].t : 0.0);
  for (std::size_t k = from; k < to; ++k) w.add(ring[k & mask].t, ring[k & mask].v);
  w.end = to;
  w.updates = 0;
  return w;
}

}  // namespace spindown
