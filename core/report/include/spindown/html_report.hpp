#pragma once
// A lab session as one self-contained HTML page (`spindown report`): inline CSS and inline SVG
// only (no scripts, fonts, images or links to anything outside the page), every text taken
// from files escaped. Per bench and run: the measured curve with each model's fit and the
// residuals, the coefficient table with standard errors in SI and the lab's units, the
// explain story and the health verdict; first, a summary across benches and runs (health,
// and which motors drift: c_v and c_c over runs in time order with a trend ± its error).
#include <string>
#include <string_view>

#include "spindown/session_report.hpp"

namespace spindown {

struct HtmlReportOptions {
  std::string title = "spindown report";
  std::string generated;  // shown in the header ("2026-11-22 01:30 UTC"); empty = not shown
};

std::string render_html_report(const SessionReport& report, const HtmlReportOptions& options = {});

// One run's figure: measured samples, every model's curve, and the residuals (class "run-plot").
std::string run_figure_svg(const ReportRun& run);
// A bench's c_v and c_c over its runs with error bars and the trend line (class "trend-plot").
std::string trend_figure_svg(const BenchSummary& bench);

// Escapes & < > " ' for HTML text and attribute values.
std::string html_escape(std::string_view text);

}  // namespace spindown
