#pragma once
// A class's table: one row per run across many files (every student's recording), as CSV for a
// spreadsheet or as a JSON array of the same rows. `spindown fit --table csv|json`. The CSV in
// either style of csv_cells.hpp: ',' and decimal points, or ';' and decimal commas for a European
// Excel; a file for a spreadsheet starts with a byte-order mark.
//
// Columns, SI units (as `spindown export`):
//   file, bench, student       the file as named; its bench and student (roster, --bench-pattern,
//                              an LCM log's bench id); empty when nothing named them
//   run, t_cut_s, t_stop_s, stopped, samples
//   best                       the model spindown trusts (fit's "best")
//   trust                      "ok", or "doubtful" when a doubt below applies
//   doubts                     fit's doubts joined by " | " (units, a model that misses, …)
//   c1 (viscous model, N·m·s/rad), c2 (Coulomb model, N·m), c3, c4 (combined model), each with
//   _stderr (statistical) and _total_stderr (with J's and K_b's own uncertainty)
//   omega0, omega0_stderr      of the best model (rad/s)
//   rmse, residual_unit, reduced_chi2 of the best model; reading_noise (σ of one reading, as fit
//                              and explain give it)
//   health, health_reason      the verdict against the bench's --bench-config reference
//                              (ok | check | service | not_judged; empty: no bench file)
//   J_kg_m2, J_rel_error, Kb_V_s_per_rad, Kb_rel_error
#include <string>

#include "spindown/csv_cells.hpp"
#include "spindown/fit_report.hpp"

namespace spindown {

// The header line, with its newline (after the style's byte-order mark, when it has one).
std::string run_table_csv_header(const CsvStyle& style = {});
// One line per run of the file, each with its newline.
std::string run_table_csv_rows(const FileFit& file, const CsvStyle& style = {});

// The file's rows as JSON objects (the same columns as keys; numbers, null for none), appended to
// an array being written ("[" before the first file, "\n]" after the last): each row starts on a
// new line indented two spaces, with a comma before all but the very first row.
void append_run_table_json_rows(const FileFit& file, std::string& out, bool& first_row);

}  // namespace spindown
