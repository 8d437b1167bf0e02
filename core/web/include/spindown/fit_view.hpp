#pragma once
// A FIT message as spindown-web's pages show it: the numbers exactly as the message carries them
// (SI value and standard error of each coefficient), their text in the lab's units with ±
// errors (format_value_error, lab_unit_for: what `spindown fit --lab-units` prints), the health
// verdict in words, the doubts; and for the bench page each model's curve (zero level + k·ω(τ)
// from the message's ω0, c/J) and the best model's residuals against the run's samples.
#include <cstddef>
#include <optional>
#include <string>

#include <spindown/explain_t.hpp>
#include <spindown/fit_t.hpp>

#include "spindown/fit_report.hpp"
#include "spindown/run_trace.hpp"

namespace spindown {

// A finite number, or null (JSON has no NaN or infinity).
Json json_number(double v);

// A point of a plot, [x, y] to the plots' resolution (x to 0.1 ms, y to 7 significant digits,
// each the decimal's nearest double): shorter JSON for the pages; the CSV keeps every digit.
Json plot_point(double x, double y);

// "ok", "check", "service" or "not judged" (no reference, or no bench file: verdict "").
std::string health_text(const fit_t& msg);

// {"run","partial","best","best_reason","c1".."c4":{"value","stderr","unit","text","model"}|absent,
//  "health","health_reason","doubts":[…],"rmse","residual_unit","t_cut_s","t_stop_s","t_end_s","end"}
// c1/c2 from the viscous/Coulomb model, c3/c4 from the combined one (whichever is best).
Json fit_summary_json(const fit_t& msg, bool lab_units);

// The best model's curve for a small plot: up to points [τ, reading] pairs from the cut to the end
// of the fitted window; empty when the message has no usable best model.
Json best_curve_json(const fit_t& msg, std::size_t points);

// {"models":[{"name","converged","rmse","t_stop_pred_s","message","curve":[[τ,v]…]}…],
//  "residuals":{"model","points":[[τ,r]…]}|null} — τ in seconds after the message's cut.
// trace: the run's samples (residuals over those inside the fitted window; null: none).
// nullopt and *why when the message is inconsistent (from_fit_message's words).
std::optional<Json> fit_curves_json(const fit_t& msg, const RunTrace* trace, std::size_t curve_points,
                                    std::size_t max_residuals, std::string* why = nullptr);

// The EXPLAIN story: {"run","base":[…],"rmse_base","rmse_final","noise_level","steps":[{"added","why",
// "rmse_before","rmse_after","where":[{"t_from_s","t_to_s","mean_residual"}]}],"final":[…],
// "params":[{"name","value","stderr","unit","text"}],"story"}.
Json explain_json(const explain_t& msg, bool lab_units);

}  // namespace spindown
