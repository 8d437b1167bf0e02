#include "spindown/svg_plot.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>

#include "spindown/utf8_text.hpp"

namespace spindown::svg {

std::vector<double> nice_ticks(double lo, double hi, int target) {
  std::vector<double> out;
  if (!(hi > lo)) return {lo};
  const double raw = (hi - lo) / target;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = mag;
  for (double m : {1.0, 2.0, 2.5, 5.0, 10.0})
    if (m * mag >= raw) {
      step = m * mag;
      break;
    }
  for (double t = std::ceil(lo / step) * step; t <= hi + 1e-9 * step && out.size() < 50; t += step)
    out.push_back(std::abs(t) < 1e-12 * step ? 0.0 : t);
  return out;
}

std::string escape(std::string_view in) {
  std::string out;
  out.reserve(in.size());
  for (char c : in) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string axes(const Panel& p, const std::string& xlabel, const std::string& ylabel) {
  std::string s = fmt::format("<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"none\" "
                              "stroke=\"#444\"/>\n",
                              p.x, p.y, p.w, p.h);
  for (double t : nice_ticks(p.x0, p.x1)) {
    const double x = p.px(t);
    s += fmt::format("<line x1=\"{0:.1f}\" y1=\"{1:.1f}\" x2=\"{0:.1f}\" y2=\"{2:.1f}\" stroke=\"#ddd\"/>\n", x, p.y,
                     p.y + p.h);
    s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\">{:g}</text>\n", x, p.y + p.h + 16, t);
  }
  for (double t : nice_ticks(p.y0, p.y1)) {
    const double y = p.py(t);
    s += fmt::format("<line x1=\"{0:.1f}\" y1=\"{1:.1f}\" x2=\"{2:.1f}\" y2=\"{1:.1f}\" stroke=\"#ddd\"/>\n", p.x, y,
                     p.x + p.w);
    s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"end\">{:g}</text>\n", p.x - 6, y + 4, t);
  }
  s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\">{}</text>\n", p.x + p.w / 2,
                   p.y + p.h + 34, escape(xlabel));
  s += fmt::format("<text transform=\"translate({:.1f},{:.1f}) rotate(-90)\" text-anchor=\"middle\">{}</text>\n",
                   p.x - 52, p.y + p.h / 2, escape(ylabel));
  return s;
}

std::string polyline(const Panel& p, std::span<const double> xs, std::span<const double> ys, std::string_view style) {
  std::string pts;
  pts.reserve(xs.size() * 14);
  const std::size_t n = std::min(xs.size(), ys.size());
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(ys[i]) || !std::isfinite(xs[i])) continue;
    pts += fmt::format("{:.1f},{:.1f} ", p.px(xs[i]), p.py(std::clamp(ys[i], p.y0, p.y1)));
  }
  return fmt::format("<polyline fill=\"none\" {} points=\"{}\"/>\n", style, pts);
}

std::string dots(const Panel& p, std::span<const double> xs, std::span<const double> ys, std::size_t stride,
                 double radius, std::string_view fill) {
  std::string s;
  stride = std::max<std::size_t>(stride, 1);
  const std::size_t n = std::min(xs.size(), ys.size());
  for (std::size_t i = 0; i < n; i += stride) {
    if (!std::isfinite(ys[i]) || !std::isfinite(xs[i])) continue;
    s += fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"{:g}\" fill=\"{}\"/>\n", p.px(xs[i]),
                     p.py(std::clamp(ys[i], p.y0, p.y1)), radius, fill);
  }
  return s;
}

std::string legend(double x, double y, const std::vector<std::pair<std::string, std::string>>& items, double width) {
  // A label wider than the box (about 6.6 px a character at 12 px) goes on as many lines as it
  // needs, broken at spaces, so that nothing of it falls outside the box or the figure.
  const std::size_t room = static_cast<std::size_t>(std::max(10.0, (width - 52) / 6.6));
  std::vector<std::vector<std::string>> lines(items.size());
  std::size_t total = 0;
  for (std::size_t i = 0; i < items.size(); ++i) {
    std::string_view rest = items[i].first;
    while (!rest.empty()) {
      std::size_t cut = utf8_prefix_bytes(rest, room);
      if (cut < rest.size()) {
        const std::size_t space = rest.substr(0, cut).rfind(' ');
        if (space != std::string_view::npos && space > 0) cut = space + 1;  // the space stays, at the line's end
      }
      lines[i].emplace_back(rest.substr(0, cut));
      rest.remove_prefix(cut);
    }
    if (lines[i].empty()) lines[i].emplace_back();
    total += lines[i].size();
  }
  std::string s = fmt::format("<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:g}\" height=\"{}\" fill=\"white\" "
                              "fill-opacity=\"0.85\" stroke=\"#999\"/>\n",
                              x, y, width, 8 + 18 * total);
  std::size_t line = 0;
  for (std::size_t i = 0; i < items.size(); ++i) {
    const double yy = y + 16 + 18.0 * static_cast<double>(line);
    s += fmt::format("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" {}/>\n", x + 8, yy - 4, x + 38,
                     yy - 4, items[i].second);
    s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\">", x + 46, yy);
    for (std::size_t k = 0; k < lines[i].size(); ++k)
      s += k == 0 ? escape(lines[i][k])
                  : fmt::format("<tspan x=\"{:.1f}\" dy=\"18\">{}</tspan>", x + 46, escape(lines[i][k]));
    s += "</text>\n";
    line += lines[i].size();
  }
  return s;
}

void bin_means(std::span<const double> x, std::span<const double> r, std::size_t m, std::vector<double>& bx,
               std::vector<double>& by) {
  m = std::max<std::size_t>(m, 1);
  const std::size_t n = std::min(x.size(), r.size());
  for (std::size_t i = 0; i < n; i += m) {
    const std::size_t e = std::min(i + m, n);
    double sx = 0, sy = 0;
    for (std::size_t j = i; j < e; ++j) sx += x[j], sy += r[j];
    bx.push_back(sx / static_cast<double>(e - i));
    by.push_back(sy / static_cast<double>(e - i));
  }
}

}  // namespace spindown::svg
