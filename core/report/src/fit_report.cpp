#include "spindown/fit_report.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <sstream>

#include <fmt/format.h>

#include "spindown/health_report.hpp"
#include "spindown/lab_units.hpp"
#include "spindown/quantity.hpp"

namespace spindown {

namespace {

bool is_curve_constant(const Parameter& p) { return p.name == "A" || p.name == "B" || p.name == "C"; }

const char* severity_name(Diagnostic::Severity s) {
  switch (s) {
    case Diagnostic::Severity::error: return "error";
    case Diagnostic::Severity::warning: return "warning";
    case Diagnostic::Severity::note: return "note";
  }
  return "warning";
}

std::size_t samples_in(const Run& run) {
  return run.end_index > run.cut_index ? run.end_index - run.cut_index : 0;
}

// Display width of UTF-8 text: code points, not bytes (·, ², ω, ± are multibyte).
std::size_t display_width(std::string_view s) {
  return static_cast<std::size_t>(
      std::count_if(s.begin(), s.end(), [](char c) { return (static_cast<unsigned char>(c) & 0xC0) != 0x80; }));
}

std::vector<std::string> split_lines(const std::string& s) {
  std::vector<std::string> lines;
  std::istringstream in(s);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  if (lines.empty()) lines.emplace_back();
  return lines;
}

// A left-aligned table whose cells may span several lines.
std::string render_table(const std::vector<std::vector<std::string>>& rows, std::string_view indent) {
  if (rows.empty()) return {};
  const std::size_t ncol = rows.front().size();
  std::vector<std::vector<std::vector<std::string>>> cells;
  std::vector<std::size_t> width(ncol, 0);
  for (const auto& row : rows) {
    auto& r = cells.emplace_back();
    for (std::size_t c = 0; c < ncol; ++c) {
      r.push_back(split_lines(c < row.size() ? row[c] : std::string{}));
      for (const auto& l : r.back()) width[c] = std::max(width[c], display_width(l));
    }
  }
  // Rows that span several lines are kept apart by a blank line.
  bool tall_rows = false;
  for (std::size_t ri = 1; ri < cells.size(); ++ri)
    for (const auto& cell : cells[ri]) tall_rows = tall_rows || cell.size() > 1;
  std::string out;
  for (std::size_t ri = 0; ri < cells.size(); ++ri) {
    if (tall_rows && ri > 1) out += '\n';
    std::size_t height = 0;
    for (const auto& cell : cells[ri]) height = std::max(height, cell.size());
    for (std::size_t li = 0; li < height; ++li) {
      std::string line(indent);
      for (std::size_t c = 0; c < ncol; ++c) {
        const std::string text = li < cells[ri][c].size() ? cells[ri][c][li] : std::string{};
        line += text;
        if (c + 1 < ncol) line.append(width[c] - display_width(text) + 2, ' ');
      }
      while (!line.empty() && line.back() == ' ') line.pop_back();
      out += line + '\n';
    }
    if (ri == 0) {  // rule under the header
      std::size_t total = 0;
      for (std::size_t c = 0; c < ncol; ++c) total += width[c] + (c + 1 < ncol ? 2 : 0);
      out += std::string(indent) + std::string(total, '-') + '\n';
    }
  }
  return out;
}

std::string display_name(const Parameter& p) { return p.name == "omega0" ? "ω0" : p.name; }

std::string with_unit(std::string text, std::string_view ascii_unit) {
  if (ascii_unit.empty()) return text;
  return text + " " + std::string(pretty_unit(ascii_unit));
}

std::string coefficient_cell(const ModelFit& m, const ReportOptions& opt) {
  std::string cell;
  for (const auto& p : m.params) {
    if (is_curve_constant(p)) continue;
    if (!cell.empty()) cell += '\n';
    cell += display_name(p) + " = " + with_unit(format_value_error(p.value, p.std_error), p.unit);
    if (opt.lab_units)
      if (auto lab = lab_unit_for(p.unit))
        cell += fmt::format(" = {} {}", format_value_error(p.value * lab->per_si, p.std_error * lab->per_si),
                            lab->pretty);
  }
  return cell.empty() ? "-" : cell;
}

std::string curve_cell(const ModelFit& m) {
  std::string cell;
  for (const auto& p : m.params) {
    if (!is_curve_constant(p)) continue;
    if (!cell.empty()) cell += '\n';
    cell += p.name + " = " + with_unit(fmt::format("{:.6g}", p.value), p.unit);
  }
  return cell.empty() ? "-" : cell;
}

std::string stop_cell(double t_stop_pred_s) {
  return std::isfinite(t_stop_pred_s) ? fmt::format("{:.2f} s", t_stop_pred_s) : std::string("never");
}

// The lowest-BIC converged model other than the best, to compare against.
const ModelFit* runner_up(const RunFit& fit, const ModelFit* best) {
  const ModelFit* second = nullptr;
  for (const auto& m : fit.models) {
    if (&m == best || !m.converged || !std::isfinite(m.bic)) continue;
    if (!second || m.bic < second->bic) second = &m;
  }
  return second;
}

const ModelFit* best_model(const RunFit& fit) {
  for (const auto& m : fit.models)
    if (model_name(m.kind) == fit.best) return &m;
  return nullptr;
}

// Kass & Raftery's reading of a BIC difference.
std::string_view evidence(double delta_bic) {
  if (delta_bic > 10) return "very strong";
  if (delta_bic > 6) return "strong";
  if (delta_bic > 2) return "positive";
  return "weak";
}

}  // namespace

std::string format_value_error(double value, double std_error) {
  if (!std::isfinite(value)) return fmt::format("{}", value);
  if (!std::isfinite(std_error) || std_error <= 0) {
    const std::string v = fmt::format("{:.6g}", value);
    return std::isnan(std_error) || std::isinf(std_error) ? v + " ± ?" : v;
  }
  const int err_exp = static_cast<int>(std::floor(std::log10(std_error)));
  const int val_exp = value != 0 ? static_cast<int>(std::floor(std::log10(std::fabs(value)))) : err_exp;
  const int magnitude = std::max(val_exp, err_exp);
  if (magnitude >= -3 && magnitude < 6) {
    const int decimals = std::clamp(1 - err_exp, 0, 12);
    return fmt::format("{:.{}f} ± {:.{}f}", value, decimals, std_error, decimals);
  }
  // Shared exponent: both numbers as mantissas of 10^magnitude, error to two digits.
  const double scale = std::pow(10.0, magnitude);
  const int decimals = std::clamp(magnitude - err_exp + 1, 0, 12);
  return fmt::format("({:.{}f} ± {:.{}f})e{:+03d}", value / scale, decimals, std_error / scale, decimals, magnitude);
}

std::string explain_best(const RunFit& fit) {
  if (!fit.best_reason.empty()) return fit.best_reason;
  const ModelFit* best = best_model(fit);
  if (!best) return "no model converged";
  const ModelFit* second = runner_up(fit, best);
  if (!second)
    return fmt::format("{} is the only model {}", fit.best, fit.models.size() == 1 ? "asked for" : "that converged");
  const double delta = second->bic - best->bic;
  return fmt::format("lowest BIC: ΔBIC = {:.1f} below {} ({} evidence); RMSE {:.4g} vs {:.4g}", delta,
                     model_name(second->kind), evidence(delta), best->rmse, second->rmse);
}

namespace {

constexpr bool is_plain_char(unsigned char c) { return c >= 0x20 && c <= 0x7E && c != '"' && c != '\\'; }

// Printable ASCII without '"' or '\\': a JSON string of it is the text in quotes. Sixteen bytes
// at a time with GCC's vector extension (the long values: reasons, sources, messages).
bool is_plain(std::string_view s) {
  using Bytes = unsigned char __attribute__((vector_size(16)));
  const auto* p = reinterpret_cast<const unsigned char*>(s.data());
  const std::size_t n = s.size();
  std::size_t i = 0;
  for (; n - i >= sizeof(Bytes); i += sizeof(Bytes)) {
    Bytes b;
    std::memcpy(&b, p + i, sizeof b);
    const auto escaped = (b < 0x20) | (b > 0x7E) | (b == '"') | (b == '\\');
    std::uint64_t lanes[2];
    std::memcpy(lanes, &escaped, sizeof lanes);
    if ((lanes[0] | lanes[1]) != 0) return false;
  }
  for (; i < n; ++i)
    if (!is_plain_char(p[i])) return false;
  return true;
}

// A member name written in the source: checked when compiling to need no escape, so the writer
// copies it as it is.
class PlainKey {
 public:
  template <std::size_t N>
  consteval PlainKey(const char (&text)[N]) : text_(text, N - 1) {  // NOLINT: implicit on purpose
    for (char c : text_)
      if (!is_plain_char(static_cast<unsigned char>(c))) throw "a PlainKey is printable ASCII without '\"' or '\\'";
  }
  std::string_view text() const { return text_; }

 private:
  std::string_view text_;
};

// Writes JSON laid out as nlohmann's dump(2, ' ', false, error_handler_t::replace): "{" then each
// member on its own line indented two more, "key": value, ",\n" between members, the closing
// bracket on its own line at the container's indent; "{}" and "[]" when empty.
//
// The text goes straight into out's bytes through a cursor (room made ahead, doubling; out is cut
// to what was written when the writer goes): a member is a few small copies, where
// std::string's appends cost more than the bytes (a file's JSON is ~60 members).
class PrettyJsonWriter {
 public:
  PrettyJsonWriter(std::string& out, std::size_t indent) : out_(out), size_(out.size()), indent_(indent) {
    out_.resize(std::max(out_.capacity(), size_ + 256));
  }
  ~PrettyJsonWriter() { out_.resize(size_); }
  PrettyJsonWriter(const PrettyJsonWriter&) = delete;
  PrettyJsonWriter& operator=(const PrettyJsonWriter&) = delete;

  void begin_object() { open('{'); }
  void end_object() { close('}'); }
  void begin_array() { open('['); }
  void end_array() { close(']'); }

  // A member's key; its value follows.
  void key(PlainKey k) {
    next_element();
    quoted_key(k.text());
  }
  // A key only known at run time (a parameter's name): escaped when it needs it.
  void runtime_key(std::string_view k) {
    next_element();
    if (!is_plain(k)) {
      string(k);
      put(": ");
      return;
    }
    quoted_key(k);
  }
  // An array element's start; its value follows.
  void element() { next_element(); }

  void string(std::string_view s) {
    if (is_plain(s)) {
      char* p = room(s.size() + 2);
      *p++ = '"';
      std::memcpy(p, s.data(), s.size());
      p[s.size()] = '"';
      size_ += s.size() + 2;
    } else {  // escapes and bytes that are not UTF-8: nlohmann's own serializer, exactly
      put(Json(s).dump(-1, ' ', false, Json::error_handler_t::replace));
    }
  }
  void number(double x) {  // JSON has no inf/NaN: a stop that never comes or an undefined R² is null
    if (!std::isfinite(x)) {
      put("null");
      return;
    }
    // The shortest digits that read back as x: what dump() writes for a double (the same
    // function), without building a Json and a string per number.
    constexpr std::size_t most = 64;  // to_chars needs max_digits10 + a sign, point and exponent
    char* p = room(most);
    size_ += static_cast<std::size_t>(nlohmann::detail::to_chars(p, p + most, x) - p);
  }
  void integer(std::int64_t n) { put(std::string_view(fmt::format_int(n).c_str())); }
  void unsigned_integer(std::size_t n) { put(std::string_view(fmt::format_int(n).c_str())); }
  void boolean(bool b) { put(b ? std::string_view("true") : std::string_view("false")); }
  void null() { put("null"); }

  // Shorthands for a member and its value.
  void member(PlainKey k, std::string_view v) {
    key(k);
    string(v);
  }
  void member(PlainKey k, const char* v) { member(k, std::string_view(v)); }
  void member_number(PlainKey k, double x) {
    key(k);
    number(x);
  }
  void member(PlainKey k, bool b) {
    key(k);
    boolean(b);
  }

 private:
  // ",\n" and the spaces of the deepest indent the documents use, so a member's line break and
  // indent are one copy.
  static constexpr std::size_t layout_spaces = 126;
  static constexpr std::array<char, 2 + layout_spaces> layout = [] {
    std::array<char, 2 + layout_spaces> a{};
    a[0] = ',';
    a[1] = '\n';
    for (std::size_t i = 2; i < a.size(); ++i) a[i] = ' ';
    return a;
  }();

  // Room for n more bytes at the cursor.
  char* room(std::size_t n) {
    if (out_.size() - size_ < n) out_.resize(std::max(2 * out_.size(), size_ + n));
    return out_.data() + size_;
  }
  void put(std::string_view s) {
    std::memcpy(room(s.size()), s.data(), s.size());
    size_ += s.size();
  }
  void quoted_key(std::string_view k) {  // "k": , k needing no escape
    char* p = room(k.size() + 4);
    *p++ = '"';
    std::memcpy(p, k.data(), k.size());
    std::memcpy(p + k.size(), "\": ", 3);
    size_ += k.size() + 4;
  }
  // A line break, then the indent.
  void new_line(bool comma) {
    if (indent_ > layout_spaces) {  // deeper than any document here: not worth a faster way
      put(comma ? ",\n" : "\n");
      put(std::string(indent_, ' '));
      return;
    }
    const std::size_t skip = comma ? 0 : 1, n = 2 - skip + indent_;
    std::memcpy(room(n), layout.data() + skip, n);
    size_ += n;
  }

  void open(char bracket) {
    put(std::string_view(&bracket, 1));
    empty_.push_back(true);
    indent_ += 2;
  }
  void close(char bracket) {
    indent_ -= 2;
    if (!empty_.back()) new_line(false);
    empty_.pop_back();
    put(std::string_view(&bracket, 1));
  }
  void next_element() {
    new_line(!empty_.back());
    empty_.back() = false;
  }

  std::string& out_;
  std::size_t size_;  // bytes of out_ written; the rest is room
  std::size_t indent_;
  std::vector<bool> empty_;  // per open container: nothing written in it yet
};

// A Json object keeps one member per key (a repeated key overwrites the first in place); the
// writer does not, so the text of a run with repeated parameter names is its document's dump.

bool has_repeated_param_names(const RunFit& run) {
  for (const auto& m : run.models)
    for (std::size_t i = 0; i < m.params.size(); ++i)
      for (std::size_t j = 0; j < i; ++j)
        if (m.params[i].name == m.params[j].name) return true;
  return false;
}

bool has_repeated_param_names(const FileFit& file) {
  return std::any_of(file.runs.begin(), file.runs.end(),
                     [](const RunFit& run) { return has_repeated_param_names(run); });
}

// The `fit --json` contract of one run (with the tags when given); leaves the run's object open
// (a file's entry adds "health" last).
void write_run_fit(PrettyJsonWriter& w, const RunFit& fit, const ReportOptions& opt, const RunTags* tags = nullptr) {
  const std::string_view residual_unit = quantity_unit(fit.quantity);
  const Run& run = fit.run;
  w.begin_object();
  w.key("run"); w.integer(run.number);
  w.member_number("t_cut_s", run.t_cut_s);
  w.key("t_stop_s");
  if (run.stopped) w.number(run.t_stop_s);
  else w.null();
  w.key("samples"); w.unsigned_integer(samples_in(run));
  w.key("models");
  w.begin_array();
  for (const auto& m : fit.models) {
    w.element();
    w.begin_object();
    w.member("name", model_name(m.kind));
    w.key("params");
    w.begin_object();
    for (const auto& p : m.params) {
      w.runtime_key(p.name);
      w.begin_object();
      w.member_number("value", p.value);
      w.member_number("stderr", p.std_error);
      w.member("unit", p.unit);
      if (opt.lab_units)
        if (auto lab = lab_unit_for(p.unit)) {
          w.key("lab");
          w.begin_object();
          w.member_number("value", p.value * lab->per_si);
          w.member_number("stderr", p.std_error * lab->per_si);
          w.member("unit", lab->ascii);
          w.end_object();
        }
      w.end_object();
    }
    w.end_object();
    w.member_number("rmse", m.rmse);
    w.member("residual_unit", residual_unit);
    w.member_number("r2", m.r2);
    w.member_number("aic", m.aic);
    w.member_number("bic", m.bic);
    w.member_number("t_stop_pred_s", m.t_stop_pred_s);
    w.key("n"); w.unsigned_integer(m.n);
    w.member("converged", m.converged);
    if (!m.message.empty()) w.member("message", m.message);
    w.end_object();
  }
  w.end_array();
  w.key("best");
  if (fit.best.empty()) w.null();
  else w.string(fit.best);
  w.member("best_reason", explain_best(fit));
  w.member("stopped", run.stopped);
  w.member("end", end_name(run.end));
  w.member_number("t_end_s", run.t_end_s);
  w.member("lead_in", run.lead_in);
  w.member_number("zero_level", run.zero_level);
  w.member_number("noise_level", run.noise_level);
  w.member_number("period_s", run.period_s);
  w.member("quantity", residual_unit);
  w.key("bench");
  w.begin_object();
  w.member_number("J", fit.bench.inertia_kg_m2);
  w.member("J_unit", "kg*m^2");
  w.member("J_source", fit.bench.inertia_source);
  w.member_number("Kb", fit.bench.kb_v_s_per_rad);
  w.member("Kb_unit", "V*s/rad");
  w.member("Kb_source", fit.bench.kb_source);
  if (opt.lab_units) {
    w.key("J_lab");
    w.begin_object();
    w.member_number("value", inertia_to_g_cm2(fit.bench.inertia_kg_m2));
    w.member("unit", "g*cm^2");
    w.end_object();
  }
  if (tags) w.member("id", tags->bench_id);
  w.end_object();
  if (tags && tags->has_seq) {
    w.key("first_seq"); w.integer(tags->first_seq);
    w.key("last_seq"); w.integer(tags->last_seq);
  }
}

// A run's "health" object.
void write_health(PrettyJsonWriter& w, const HealthVerdict& v) {
  w.begin_object();
  w.member("level", health_level_name(v.level));
  w.member("reason", v.reason);
  w.member("has_reference", v.has_reference);
  w.key("findings");
  w.begin_array();
  for (const auto& f : v.findings) {
    w.element();
    w.begin_object();
    w.member("what", f.what);
    w.member("level", health_level_name(f.level));
    w.member("reason", f.reason);
    w.member_number("value", f.value);
    w.member_number("stderr", f.std_error);
    w.member_number("reference", f.reference);
    w.member_number("reference_stderr", f.reference_std_error);
    w.member("reference_name", f.reference_name);
    w.member_number("ratio", f.ratio);
    w.member_number("ratio_stderr", f.ratio_std_error);
    w.member("unit", f.unit);
    w.end_object();
  }
  w.end_array();
  w.end_object();
}

// One file's entry of the contract; the writer is done (out cut to its text) on return.
void write_file_fit(std::string& out, std::size_t indent, const FileFit& file, const ReportOptions& opt) {
  PrettyJsonWriter w(out, indent);
  w.begin_object();
  w.member("file", file.file);
  w.key("runs");
  w.begin_array();
  for (std::size_t i = 0; i < file.runs.size(); ++i) {
    w.element();
    if (i < file.run_bench.size()) {
      const RunTags bench{file.run_bench[i], 0, 0, false};
      write_run_fit(w, file.runs[i], opt, &bench);
    } else {
      write_run_fit(w, file.runs[i], opt);
    }
    if (i < file.health.size() && file.health[i]) {
      w.key("health");
      write_health(w, *file.health[i]);
    }
    w.end_object();
  }
  w.end_array();
  w.key("samples_read"); w.unsigned_integer(file.samples);
  w.key("lines_read"); w.unsigned_integer(file.lines_read);
  w.key("lines_skipped"); w.unsigned_integer(file.lines_skipped);
  w.key("diagnostics");
  w.begin_array();
  for (const auto& d : file.diagnostics) {
    w.element();
    w.begin_object();
    w.member("severity", severity_name(d.severity));
    w.key("line"); w.integer(d.line);
    w.member("message", d.message);
    w.end_object();
  }
  w.end_array();
  w.key("failures");
  w.begin_array();
  for (const auto& why : file.failures) {
    w.element();
    w.string(why);
  }
  w.end_array();
  w.end_object();
}

}  // namespace

std::string file_fit_json_text(const FileFit& file, const ReportOptions& opt) {
  constexpr std::size_t indent = 4;  // inside {"files": [ … ]}
  std::string out(indent, ' ');
  if (has_repeated_param_names(file)) {
    const std::string text = file_fit_json(file, opt).dump(2, ' ', false, Json::error_handler_t::replace);
    for (char c : text) {
      out += c;
      if (c == '\n') out.append(indent, ' ');  // a raw newline in a dump is always layout
    }
    return out;
  }
  out.reserve(2048 + 3072 * file.runs.size() + 128 * file.diagnostics.size());
  write_file_fit(out, indent, file, opt);
  return out;
}

namespace {

// The writer's text of one run (tags when given), its object closed.
std::string run_fit_text(const RunFit& fit, const ReportOptions& opt, const RunTags* tags) {
  std::string out;
  {
    PrettyJsonWriter w(out, 0);
    write_run_fit(w, fit, opt, tags);
    w.end_object();
  }
  return out;
}

}  // namespace

// The documents are the writer's text read back: one writer of the contract. Numbers are the
// shortest digits that read back as the same double, so nothing is lost on the way.
Json run_fit_json(const RunFit& fit, const ReportOptions& opt) { return Json::parse(run_fit_text(fit, opt, nullptr)); }

Json tagged_run_fit_json(const RunFit& fit, const RunTags& tags, const ReportOptions& opt) {
  return Json::parse(run_fit_text(fit, opt, &tags));
}

Json health_json(const HealthVerdict& v) {
  std::string out;
  {
    PrettyJsonWriter w(out, 0);
    write_health(w, v);
  }
  return Json::parse(out);
}

Json file_fit_json(const FileFit& file, const ReportOptions& opt) {
  std::string out;
  write_file_fit(out, 0, file, opt);
  return Json::parse(out);
}

Json fit_report_json(std::span<const FileFit> files, const ReportOptions& opt) {
  Json list = Json::array();
  for (const auto& f : files) list.push_back(file_fit_json(f, opt));
  return Json{{"files", std::move(list)}};
}

void tag_run_json(Json& run, const RunTags& tags) {
  // As tagged_run_fit_json's text reads back (a non-negative integer parses as unsigned), so the
  // two documents of one run compare equal member for member (refit --compare).
  const auto as_read_back = [](std::int64_t v) { return v >= 0 ? Json(static_cast<std::uint64_t>(v)) : Json(v); };
  run["bench"]["id"] = tags.bench_id;
  if (!tags.has_seq) return;
  run["first_seq"] = as_read_back(tags.first_seq);
  run["last_seq"] = as_read_back(tags.last_seq);
}

void append_run_fit_json_text(std::string& out, const RunFit& fit, const ReportOptions& opt, std::size_t indent,
                              const RunTags* tags) {
  if (has_repeated_param_names(fit)) {
    const Json j = tags ? tagged_run_fit_json(fit, *tags, opt) : run_fit_json(fit, opt);
    for (char c : j.dump(2, ' ', false, Json::error_handler_t::replace)) {
      out += c;
      if (c == '\n') out.append(indent, ' ');  // a raw newline in a dump is always layout
    }
    return;
  }
  PrettyJsonWriter w(out, indent);
  write_run_fit(w, fit, opt, tags);
  w.end_object();
}

void FitReportJsonText::add(std::string_view file_json, std::string& out) {
  out += any_ ? ",\n" : "{\n  \"files\": [\n";
  out += file_json;
  any_ = true;
}

void FitReportJsonText::finish(std::string& out) const { out += any_ ? "\n  ]\n}" : "{\n  \"files\": []\n}"; }

std::vector<std::string> summarize_diagnostics(std::span<const Diagnostic> diagnostics, std::size_t max_shown) {
  std::vector<const Diagnostic*> order;
  for (const auto& d : diagnostics) order.push_back(&d);
  auto rank = [](const Diagnostic* d) {
    return d->severity == Diagnostic::Severity::error ? 0 : d->severity == Diagnostic::Severity::warning ? 1 : 2;
  };
  std::stable_sort(order.begin(), order.end(), [&](auto* a, auto* b) { return rank(a) < rank(b); });
  std::vector<std::string> lines;
  const std::size_t shown = max_shown == 0 ? order.size() : std::min(max_shown, order.size());
  for (std::size_t i = 0; i < shown; ++i) lines.push_back(order[i]->to_string());
  if (shown < order.size()) {
    std::size_t count[3] = {0, 0, 0};
    for (std::size_t i = shown; i < order.size(); ++i) ++count[rank(order[i])];
    std::string rest;
    const char* names[3] = {"error", "warning", "note"};
    for (int s = 0; s < 3; ++s) {
      if (count[s] == 0) continue;
      if (!rest.empty()) rest += ", ";
      rest += fmt::format("{} {}{}", count[s], names[s], count[s] == 1 ? "" : "s");
    }
    lines.push_back(fmt::format("{}: ... and {} more not shown ({})", order[shown]->source, order.size() - shown, rest));
  }
  return lines;
}

std::string format_run_fit(const RunFit& fit, const ReportOptions& opt) {
  const Run& run = fit.run;
  const std::string unit(quantity_unit(fit.quantity));
  std::string out;
  // A partial coast's first sample is not its cut: the text says so (JSON keeps "t_cut_s").
  const char* from = run.partial() ? "its first sample" : "the cut";
  if (run.partial()) out += fmt::format("run {}: coast from t = {:.3f} s (its cut was not recorded)", run.number, run.t_cut_s);
  else out += fmt::format("run {}: cut at t = {:.3f} s", run.number, run.t_cut_s);
  if (run.stopped && std::isfinite(run.t_stop_s))
    out += fmt::format(", stopped at t = {:.3f} s ({:.2f} s after {}), fitted to t = {:.3f} s", run.t_stop_s,
                       run.t_stop_s - run.t_cut_s, from, run.t_end_s);
  else
    out += fmt::format(", did not stop: fitted to t = {:.3f} s ({})", run.t_end_s, end_name(run.end));
  out += fmt::format(", {} samples", samples_in(run));
  if (!run.lead_in.empty()) out += fmt::format(", lead-in: {}", run.lead_in);
  // noise_level is the spread at standstill for a run that stopped (0 when every reading there is
  // the same printed value), the coast's near the cut for one that did not: the label says which.
  out += fmt::format("\n  zero level {:.3g} {}, {} noise {:.2g} {}, period {:.1f} ms\n", run.zero_level, unit,
                     run.stopped ? "standstill" : "coast", run.noise_level, unit, run.period_s * 1e3);
  out += fmt::format("  bench: J = {:.6g} kg·m² ({}), K_b = {:.6g} V·s/rad ({})", fit.bench.inertia_kg_m2,
                     fit.bench.inertia_source, fit.bench.kb_v_s_per_rad, fit.bench.kb_source);
  if (opt.lab_units) out += fmt::format("; J = {:.6g} g·cm²", inertia_to_g_cm2(fit.bench.inertia_kg_m2));
  out += "\n\n";

  std::vector<std::vector<std::string>> rows;
  rows.push_back({"model", "curve constants", "coefficients ± standard error", "RMSE", "R²", "BIC", "stop pred."});
  for (const auto& m : fit.models) {
    std::string name(model_name(m.kind));
    if (!m.converged) name += "\n(not converged)";
    rows.push_back({name, curve_cell(m), coefficient_cell(m, opt), fmt::format("{:.4g} {}", m.rmse, unit),
                    fmt::format("{:.5f}", m.r2), fmt::format("{:.1f}", m.bic), stop_cell(m.t_stop_pred_s)});
  }
  out += render_table(rows, "  ");
  out += fit.best.empty() ? fmt::format("\n  best: none ({})\n", explain_best(fit))
                          : fmt::format("\n  best: {} — {}\n", fit.best, explain_best(fit));
  for (const auto& m : fit.models)
    if (!m.message.empty()) out += fmt::format("  {}: {}\n", model_name(m.kind), m.message);
  return out;
}

std::string format_file_fit(const FileFit& file, const ReportOptions& opt) {
  std::size_t errors = 0, warnings = 0;
  for (const auto& d : file.diagnostics) {
    if (d.severity == Diagnostic::Severity::error) ++errors;
    if (d.severity == Diagnostic::Severity::warning) ++warnings;
  }
  std::string out = fmt::format("== {}: {} samples from {} {} ({} skipped), {} run{} fitted", file.file,
                                file.samples, file.lines_read, file.lcm_log ? "messages" : "lines",
                                file.lines_skipped, file.runs.size(), file.runs.size() == 1 ? "" : "s");
  auto count = [](std::size_t n, std::string_view what) { return fmt::format("{} {}{}", n, what, n == 1 ? "" : "s"); };
  if (errors + warnings > 0) out += ", " + count(errors, "error") + ", " + count(warnings, "warning");
  out += '\n';
  if (opt.diagnostics_in_text) {
    for (const auto& line : summarize_diagnostics(file.diagnostics, opt.max_diagnostics)) out += "  " + line + '\n';
    for (const auto& why : file.failures) out += fmt::format("  not used: {}\n", why);
  }
  for (std::size_t i = 0; i < file.runs.size(); ++i) {
    if (i < file.run_bench.size() && (i == 0 || file.run_bench[i] != file.run_bench[i - 1]))
      out += fmt::format("\n-- bench {}\n", file.run_bench[i]);
    out += '\n' + format_run_fit(file.runs[i], opt);
    if (i < file.health.size() && file.health[i]) out += format_health_verdict(*file.health[i]);
  }
  return out;
}

}  // namespace spindown
