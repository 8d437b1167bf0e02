#pragma once
// `spindown export FILE --csv [-o OUT] [--fits FITS]`: an LCM log, or a text recording, as CSV
// for MATLAB/Python.
//
// Samples (OUT, or stdout): one row per sample of every SPINDOWN.<bench>.SAMPLE message, in log
// order, exactly as recorded (repeated messages and NaN values included — check seq):
//   bench,seq,device_time_s,host_time_s,value,unit,raw_adc,clock_epoch
// raw_adc is empty when the protocol does not carry it.
//
// A text recording (Arduino/PuTTY, CSV/TSV): seq is the sample's index, host_time_s NaN, raw_adc
// empty, clock_epoch the number of Arduino resets before the sample; bench by --roster or
// --bench-pattern, else the file's name.
//
// Fits (FITS; with -o OUT by default OUT with ".csv" replaced by ".fits.csv"): the log refitted
// exactly as spindown-fitter fits live (spindown refit), a text recording as `spindown fit` fits it
// (J and K_b by the same rule), one row per run and model:
//   bench,run,model,best,converged,t_cut_s,t_stop_s,stopped,samples,rmse,residual_unit,r2,aic,
//   bic,t_stop_pred_s,c1,c1_stderr,c2,c2_stderr,c3,c3_stderr,c4,c4_stderr,omega0,omega0_stderr,
//   A,A_stderr,B,B_stderr,C,C_stderr,J_kg_m2,Kb_V_s_per_rad,bench_source,zero_level
// in SI: c1, c3 in N·m·s/rad, c2, c4 in N·m, omega0 in rad/s; A, B, C are the lab's curve
// constants (viscous y = A·e^(−B·t): A in V, B in 1/s; Coulomb y = A·t + B: A in V/s, B in V;
// combined y = A + B·e^(C·t): A, B in V, C in 1/s). Empty cells: not part of that model.
//
// --csv-locale de writes ';' between cells and decimal commas for a European Excel, and its files
// start with a UTF-8 byte-order mark (csv_output.hpp); the default CSV has none.
//
// `spindown export LOG --mcap FILE`: the same samples, with the log's RUN and FIT messages, as
// MCAP for Foxglove and PlotJuggler instead (export_mcap.hpp).
#include <string>

#include "input_options.hpp"

namespace CLI {
class App;
}

namespace spindown::cli {

struct ExportCommandOptions {
  std::string log;
  bool csv = true;
  std::string out;       // samples CSV ("" or "-" = stdout)
  std::string fits;      // fits CSV ("" = derived from out, none when out is stdout)
  bool no_fits = false;
  std::string bench_regex = ".*";
  InputOptions input;  // a text recording: columns, units, --roster/--bench-pattern, J and K_b
  std::string mcap;      // MCAP file instead of CSV (export_mcap.hpp)
  std::string csv_locale;  // --csv-locale: en or de (csv_output.hpp); its files get a byte-order mark
};

void setup_export(CLI::App& app);
int run_export(const ExportCommandOptions& options);

}  // namespace spindown::cli
