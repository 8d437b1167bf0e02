#pragma once
// Small SVG plotting pieces shared by the explain figure and the HTML report: a panel that
// maps data to pixels, nice axis ticks, axes with grid and labels, polylines, dots, a
// legend box, residual bin means, and XML escaping. Output is plain SVG text (no scripts, no
// external resources), so it can stand alone or sit inline in an HTML page.
#include <cstddef>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace spindown::svg {

// "Nice" axis ticks (steps of 1, 2, 2.5, 5 × 10^k) covering [lo, hi], at most 50.
std::vector<double> nice_ticks(double lo, double hi, int target = 6);

// A plotting area: pixel rectangle and the data range it shows.
struct Panel {
  double x, y, w, h;      // pixels
  double x0, x1, y0, y1;  // data range
  double px(double v) const { return x + (v - x0) / (x1 - x0) * w; }
  double py(double v) const { return y + h - (v - y0) / (y1 - y0) * h; }
};

// Escapes & < > " for XML/HTML text and double-quoted attribute values.
std::string escape(std::string_view text);

// The frame, grid lines, tick labels and the two axis labels (escaped).
std::string axes(const Panel& p, const std::string& xlabel, const std::string& ylabel);

// A polyline through (xs[i], ys[i]), y clamped to the panel; non-finite ys are skipped.
// style is raw attribute text, e.g. stroke="#1f77b4" stroke-width="2".
std::string polyline(const Panel& p, std::span<const double> xs, std::span<const double> ys, std::string_view style);

// Dots at every stride-th point (y clamped to the panel; non-finite skipped).
std::string dots(const Panel& p, std::span<const double> xs, std::span<const double> ys, std::size_t stride,
                 double radius, std::string_view fill);

// A legend box at (x, y): one line sample and one (escaped) label per item {label, style}.
std::string legend(double x, double y, const std::vector<std::pair<std::string, std::string>>& items,
                   double width = 370);

// Means of r over consecutive groups of m samples (and the mean x of each group), for a
// readable line through noisy residuals. Appends to bx, by.
void bin_means(std::span<const double> x, std::span<const double> r, std::size_t m, std::vector<double>& bx,
               std::vector<double>& by);

}  // namespace spindown::svg
