#include "spindown/column_names.hpp"

#include <algorithm>
#include <array>
#include <numbers>

#include "spindown/ascii_lower.hpp"
#include "spindown/text_support.hpp"
#include "spindown/trim.hpp"

namespace spindown {

namespace {

// A unit as written, for matching: lower case, no blanks, µ/μ as u, ⁻¹ as ^-1, · as *, ° as deg,
// outer brackets and a trailing full stop dropped.
std::string normal_unit(std::string_view unit) {
  std::string u;
  u.reserve(unit.size());
  static constexpr std::pair<std::string_view, std::string_view> spellings[] = {
      {"\xC2\xB5", "u"},  {"\xCE\xBC", "u"},    {"\xE2\x81\xBB", "^-"}, {"\xC2\xB9", "1"},
      {"\xC2\xB7", "*"},  {"\xE2\x8B\x85", "*"}, {"\xC2\xB0", "deg"}};
  for (std::size_t i = 0; i < unit.size();) {
    bool replaced = false;
    for (const auto& [from, to] : spellings)
      if (unit.substr(i).starts_with(from)) {
        u += to;
        i += from.size();
        replaced = true;
        break;
      }
    if (replaced) continue;
    const char c = unit[i++];
    if (c == ' ' || c == '\t') continue;
    u += static_cast<char>(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c);
  }
  while (u.size() >= 2 && ((u.front() == '(' && u.back() == ')') || (u.front() == '[' && u.back() == ']') ||
                           (u.front() == '{' && u.back() == '}')))
    u = u.substr(1, u.size() - 2);
  if (u.size() > 1 && u.back() == '.') u.pop_back();
  return u;
}

template <std::size_t N>
bool one_of(const std::array<std::string_view, N>& words, std::string_view s) {
  return std::find(words.begin(), words.end(), s) != words.end();
}

constexpr std::array<std::string_view, 12> omega_names{
    "omega", "ω", "w", "angular_velocity", "angular_speed", "angular velocity", "angular speed",
    "winkelgeschwindigkeit", "omega_motor", "w_motor", "angularvelocity", "rad_per_s"};
constexpr std::array<std::string_view, 13> speed_names{
    "speed", "n", "drehzahl", "rpm", "rotational_speed", "rotational speed", "motor_speed", "motor speed",
    "geschwindigkeit", "velocity", "revs", "umdrehungen", "frequency"};
constexpr std::array<std::string_view, 15> volt_names{
    "volts", "volt", "voltage", "v", "u", "emf", "back_emf", "back-emf", "back emf", "backemf", "bemf", "a0",
    "spannung", "emk", "gegen-emk"};
constexpr std::array<std::string_view, 16> time_names{
    "time", "t", "zeit", "millis", "ms", "micros", "us", "µs", "timestamp", "zeitstempel", "seconds", "sec",
    "s", "elapsed", "elapsed_time", "time_stamp"};
constexpr std::array<std::string_view, 3> other_value_names{"value", "reading", "messwert"};

// The last word of a name ("wheel speed" -> "speed", "motor_omega" -> "omega").
std::string_view last_word(std::string_view base) {
  const std::size_t at = base.find_last_of(" _.,-");
  return at == std::string_view::npos ? base : base.substr(at + 1);
}

template <std::size_t N>
bool names(const std::array<std::string_view, N>& words, std::string_view base) {
  return one_of(words, base) || one_of(words, last_word(base));
}

bool is_unit(std::string_view written, std::string_view base) {
  const std::string u = normal_unit(written);
  return !u.empty() && (parse_time_unit(u) || parse_value_unit(u, base));
}

// Strips what separates a name from its unit: "n /" -> "n", "Zeit," -> "zeit".
std::string clean_base(std::string_view s) {
  s = trim(s);
  while (!s.empty() && (s.back() == '/' || s.back() == ',' || s.back() == ':' || s.back() == '_' || s.back() == '-'))
    s = trim(s.substr(0, s.size() - 1));
  return std::string(s);
}

}  // namespace

std::string_view time_unit_name(TimeUnit unit) {
  switch (unit) {
    case TimeUnit::s: return "s";
    case TimeUnit::ms: return "ms";
    case TimeUnit::us: return "us";
  }
  return "?";
}

std::optional<TimeUnit> parse_time_unit(std::string_view unit) {
  const std::string u = normal_unit(unit);
  static constexpr std::array<std::string_view, 8> s{"s",   "sec",     "secs",     "second",
                                                     "seconds", "sek", "sekunde", "sekunden"};
  static constexpr std::array<std::string_view, 8> ms{"ms",          "msec",         "millis",        "millisec",
                                                      "millisecond", "milliseconds", "millisekunden", "msek"};
  static constexpr std::array<std::string_view, 8> us{"us",          "usec",         "micros",        "microsec",
                                                      "microsecond", "microseconds", "mikrosekunden", "usek"};
  if (one_of(s, u)) return TimeUnit::s;
  if (one_of(ms, u)) return TimeUnit::ms;
  if (one_of(us, u)) return TimeUnit::us;
  return std::nullopt;
}

double time_units_per_second(TimeUnit unit) {
  switch (unit) {
    case TimeUnit::s: return 1.0;
    case TimeUnit::ms: return 1e3;
    case TimeUnit::us: return 1e6;
  }
  return 1.0;
}

std::optional<ValueUnit> parse_value_unit(std::string_view unit, std::string_view column_base) {
  const std::string u = normal_unit(unit);
  static constexpr std::array<std::string_view, 3> volts{"v", "volt", "volts"};
  static constexpr std::array<std::string_view, 3> millivolts{"mv", "millivolt", "millivolts"};
  static constexpr std::array<std::string_view, 20> rpm{
      "rpm",     "1/min",   "/min",    "min^-1", "min-1",    "u/min",     "umin",     "upm",    "r/min",  "rev/min",
      "revs/min", "rev/m",  "tr/min",  "umdr/min", "umdrehungen/min", "giri/min", "obr/min", "r.p.m", "rpm's", "u.p.m"};
  static constexpr std::array<std::string_view, 9> rev_per_s{"rps",  "rev/s", "revs/s", "r/s",   "u/s",
                                                             "umdr/s", "hz",  "1/sec",  "rev/sec"};
  static constexpr std::array<std::string_view, 10> rad_per_s{
      "rad/s", "rad_s", "rads", "rad/sec", "rad*s^-1", "rads^-1", "rad.s^-1", "rad/secs", "radian/s", "radians/s"};
  static constexpr std::array<std::string_view, 4> deg_per_s{"deg/s", "degrees/s", "grad/s", "deg/sec"};
  static constexpr std::array<std::string_view, 3> per_second{"1/s", "s^-1", "/s"};
  if (one_of(volts, u)) return ValueUnit{Quantity::back_emf_volts, 1, "V"};
  if (one_of(millivolts, u)) return ValueUnit{Quantity::back_emf_volts, 1e-3, "mV"};
  if (one_of(rpm, u)) return ValueUnit{Quantity::rpm, 1, "rpm"};
  if (one_of(rev_per_s, u)) return ValueUnit{Quantity::rpm, 60, "rev/s"};
  if (one_of(rad_per_s, u)) return ValueUnit{Quantity::rad_per_s, 1, "rad/s"};
  if (one_of(deg_per_s, u)) return ValueUnit{Quantity::rad_per_s, std::numbers::pi / 180, "deg/s"};
  if (one_of(per_second, u)) {
    // An angular velocity's 1/s is rad/s; a speed's (n, Drehzahl) revolutions per second.
    if (names(omega_names, ascii_lower(trim(column_base)))) return ValueUnit{Quantity::rad_per_s, 1, "rad/s"};
    return ValueUnit{Quantity::rpm, 60, "rev/s"};
  }
  return std::nullopt;
}

std::string_view value_units_read() {
  return "V, mV, rpm (U/min, 1/min, min^-1), rev/s (rps, Hz), rad/s, deg/s";
}

ColumnName describe_column(std::string_view field) {
  ColumnName c;
  c.name = text::escape_invalid_utf8(field);
  const std::string l = ascii_lower(trim(field));
  const auto split_at = [&](std::size_t base_end, std::size_t unit_begin, std::size_t unit_end) {
    c.base = clean_base(std::string_view(l).substr(0, base_end));
    c.unit = normal_unit(std::string_view(l).substr(unit_begin, unit_end - unit_begin));
  };
  // "Drehzahl [U/min]", "omega (rad/s)": square brackets always hold a unit; round ones and braces
  // when what they hold is a unit or short and unit-like ("(km/h)"), not a description ("(left wheel)").
  if (const std::size_t open = l.find_first_of("([{"); open != std::string::npos) {
    const char closer = l[open] == '(' ? ')' : l[open] == '[' ? ']' : '}';
    const std::size_t close = l.find(closer, open + 1);
    const std::size_t end = close == std::string::npos ? l.size() : close;
    const std::string_view inside = trim(std::string_view(l).substr(open + 1, end - open - 1));
    const std::string base = clean_base(std::string_view(l).substr(0, open));
    const bool unit_like = l[open] == '[' || is_unit(inside, base) ||
                           (inside.size() <= 8 && inside.find(' ') == std::string_view::npos);
    if (unit_like && !inside.empty()) {
      split_at(open, open + 1, end);
      return c;
    }
  }
  // The whole name a unit ("rpm", "U/min", "millis"): the name says it.
  if (is_unit(l, l)) {
    c.base = l;
    return c;
  }
  // "Zeit in ms", "Drehzahl in U/min".
  if (const std::size_t in = l.rfind(" in "); in != std::string::npos && in > 0 &&
                                              is_unit(std::string_view(l).substr(in + 4), l.substr(0, in))) {
    split_at(in, in + 4, l.size());
    return c;
  }
  // "t/s", "n / min^-1", "speed/rpm".
  if (const std::size_t slash = l.find('/'); slash != std::string::npos && slash > 0) {
    const std::string base = clean_base(std::string_view(l).substr(0, slash));
    if (!base.empty() && is_unit(std::string_view(l).substr(slash + 1), base)) {
      split_at(slash, slash + 1, l.size());
      return c;
    }
  }
  // "time_ms", "omega_rad_s" (the longest suffix that is a unit), "Speed RPM".
  for (std::size_t at = l.find('_'); at != std::string::npos; at = l.find('_', at + 1)) {
    if (at > 0 && is_unit(std::string_view(l).substr(at + 1), l.substr(0, at))) {
      split_at(at, at + 1, l.size());
      return c;
    }
  }
  if (const std::size_t space = l.rfind(' '); space != std::string::npos && space > 0 &&
                                              is_unit(std::string_view(l).substr(space + 1), l.substr(0, space))) {
    split_at(space, space + 1, l.size());
    return c;
  }
  c.base = l;
  return c;
}

std::string unit_cell(std::string_view field) {
  const std::string u = normal_unit(trim(field));
  return !u.empty() && (parse_time_unit(u) || parse_value_unit(u)) ? u : std::string();
}

bool is_time_name(const ColumnName& c) {
  return names(time_names, c.base) || (c.base.empty() && !c.unit.empty() && parse_time_unit(c.unit));
}

bool is_value_name(const ColumnName& c) {
  return names(volt_names, c.base) || names(speed_names, c.base) || names(omega_names, c.base) ||
         one_of(other_value_names, c.base) || implied_value_unit(c).has_value();
}

std::optional<TimeUnit> implied_time_unit(const ColumnName& c) {
  if (!c.unit.empty()) return parse_time_unit(c.unit);
  return parse_time_unit(c.base);  // "millis", "ms", "seconds"; "time" gives nothing
}

std::optional<ValueUnit> implied_value_unit(const ColumnName& c) {
  if (!c.unit.empty()) return parse_value_unit(c.unit, c.base);
  if (auto u = parse_value_unit(c.base, c.base)) return u;  // "rpm", "volts"
  if (names(volt_names, c.base)) return ValueUnit{Quantity::back_emf_volts, 1, "V"};
  if (names(omega_names, c.base)) return ValueUnit{Quantity::rad_per_s, 1, "rad/s"};
  return std::nullopt;
}

bool unknown_value_unit(const ColumnName& c) {
  return !c.unit.empty() && !parse_time_unit(c.unit) && !parse_value_unit(c.unit, c.base);
}

std::string_view likely_value_unit(const ColumnName& c) {
  if (names(omega_names, c.base)) return "rad/s";
  if (names(speed_names, c.base)) return "rpm";
  if (names(volt_names, c.base)) return "V";
  return {};
}

}  // namespace spindown
