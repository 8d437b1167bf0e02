#include "spindown/message_decode.hpp"

#include <array>
#include <bit>
#include <cstddef>
#include <exception>
#include <fmt/format.h>
#include <limits>
#include <span>
#include <string_view>

namespace spindown {

namespace {

// The wire layout of each message, field by field in .lcm order (lcmtypes/*.lcm). A unit test
// (test_message_decode) checks every layout against the generated encoder, so a field added to
// a .lcm file without updating its layout here fails the build's tests.
enum class Wire : std::uint8_t { i8, i32, i64, f64, boolean, string };

struct WireField {
  std::string_view name;
  Wire wire;
  int count_of = -1;  // index of the earlier int32 field holding the array length; -1: scalar
};

constexpr std::int64_t fixed_bytes(Wire w) {
  switch (w) {
    case Wire::i8:
    case Wire::boolean: return 1;
    case Wire::i32: return 4;
    case Wire::i64:
    case Wire::f64: return 8;
    case Wire::string: return 0;
  }
  return 0;
}

std::int32_t be32(const unsigned char* p) {
  return static_cast<std::int32_t>((std::uint32_t(p[0]) << 24) | (std::uint32_t(p[1]) << 16) |
                                   (std::uint32_t(p[2]) << 8) | std::uint32_t(p[3]));
}
std::uint64_t be64u(const unsigned char* p) { return SamplesView::load_be64(p); }

constexpr std::int64_t hash_bytes = 8;
constexpr std::int64_t string_min_bytes = 5;  // length word and the terminating NUL

bool fail(std::string* why, std::string text) {
  if (why) *why = std::move(text);
  return false;
}

bool walk(std::string_view type, std::uint64_t expected_hash, std::span<const WireField> fields,
          const void* data, std::int64_t size, std::string* why) {
  if (data == nullptr && size != 0) return fail(why, fmt::format("{}: no data", type));
  if (size < hash_bytes) return fail(why, fmt::format("{} bytes, too short for {}", size, type));
  if (size > std::numeric_limits<int>::max())
    return fail(why, fmt::format("{}: {} bytes, more than an LCM message can hold", type, size));
  const auto* d = static_cast<const unsigned char*>(data);
  const std::uint64_t hash = be64u(d);
  if (hash != expected_hash)
    return fail(why, fmt::format("not a {} (type fingerprint {:#018x}, expected {:#018x})", type, hash,
                                 expected_hash));

  std::array<std::int64_t, 64> ints{};  // int32 scalars by field index (array counts)
  std::int64_t pos = hash_bytes;
  for (std::size_t i = 0; i < fields.size(); ++i) {
    const WireField& f = fields[i];
    std::int64_t n = 1;
    if (f.count_of >= 0) {
      n = ints[static_cast<std::size_t>(f.count_of)];
      if (n < 0)
        return fail(why, fmt::format("{}: {} = {} is negative (array {})", type, fields[f.count_of].name, n,
                                     f.name));
    }
    const std::int64_t left = size - pos;
    if (f.wire != Wire::string) {
      const std::int64_t need = n * fixed_bytes(f.wire);
      if (need > left) {
        if (f.count_of >= 0)
          return fail(why, fmt::format("{}: {} = {} needs {} bytes for {}, {} left at byte {} (truncated or "
                                       "damaged)",
                                       type, fields[f.count_of].name, n, need, f.name, left, pos));
        return fail(why, fmt::format("{}: ends inside {} at byte {} (truncated)", type, f.name, pos));
      }
      if (f.wire == Wire::i32 && f.count_of < 0) ints[i] = be32(d + pos);
      pos += need;
      continue;
    }
    // Strings: a big-endian int32 length that counts the NUL, then the bytes.
    if (f.count_of < 0 && left < string_min_bytes)
      return fail(why, fmt::format("{}: ends inside {} at byte {} (truncated)", type, f.name, pos));
    if (n * string_min_bytes > left)
      return fail(why, fmt::format("{}: {} = {} strings for {} need at least {} bytes, {} left at byte {} "
                                   "(truncated or damaged)",
                                   type, fields[f.count_of].name, n, f.name, n * string_min_bytes, left, pos));
    for (std::int64_t k = 0; k < n; ++k) {
      auto name = [&] { return f.count_of >= 0 ? fmt::format("{}[{}]", f.name, k) : std::string(f.name); };
      if (size - pos < 4)
        return fail(why, fmt::format("{}: ends inside {} at byte {} (truncated)", type, name(), pos));
      const std::int64_t len = be32(d + pos);
      pos += 4;
      if (len < 1 || len > size - pos)
        return fail(why, fmt::format("{}: string {} has length {} with {} bytes left at byte {} (truncated or "
                                     "damaged)",
                                     type, name(), len, size - pos, pos - 4));
      pos += len;
    }
  }
  return true;
}

constexpr WireField samples_fields[] = {
    {"utime", Wire::i64},        {"bench", Wire::string},          {"seq", Wire::i64},
    {"clock_epoch", Wire::i32},  {"quantity", Wire::i8},           {"n", Wire::i32},
    {"device_time_us", Wire::i64, 5}, {"host_time_us", Wire::i64, 5}, {"value", Wire::f64, 5},
    {"raw_adc", Wire::i32, 5},
};

constexpr WireField config_fields[] = {
    {"utime", Wire::i64},           {"bench", Wire::string},        {"inertia_kg_m2", Wire::f64},
    {"inertia_source", Wire::string}, {"kb_v_s_per_rad", Wire::f64}, {"kb_source", Wire::string},
    {"quantity", Wire::i8},         {"adc_volts_per_count", Wire::f64}, {"adc_bits", Wire::i32},
    {"firmware", Wire::string},     {"protocol", Wire::string},     {"sample_period_s", Wire::f64},
    {"baud", Wire::i32},            {"device", Wire::string},       {"host", Wire::string},
    {"inertia_rel_error", Wire::f64}, {"kb_rel_error", Wire::f64},
};

constexpr WireField run_fields[] = {
    {"utime", Wire::i64},     {"bench", Wire::string},  {"run", Wire::i32},      {"state", Wire::i8},
    {"t_cut_s", Wire::f64},   {"t_stop_s", Wire::f64},  {"first_seq", Wire::i64}, {"last_seq", Wire::i64},
    {"samples", Wire::i32},   {"note", Wire::string},   {"lead_in", Wire::string},
};

constexpr WireField status_fields[] = {
    {"utime", Wire::i64},              // 0
    {"service", Wire::string},         // 1
    {"instance", Wire::string},        // 2
    {"host", Wire::string},            // 3
    {"pid", Wire::i32},                // 4
    {"state", Wire::string},           // 5
    {"uptime_s", Wire::f64},           // 6
    {"ncounters", Wire::i32},          // 7
    {"counter_name", Wire::string, 7},  // 8
    {"counter_value", Wire::i64, 7},   // 9
    {"ngauges", Wire::i32},            // 10
    {"gauge_name", Wire::string, 10},  // 11
    {"gauge_value", Wire::f64, 10},    // 12
    {"last_error", Wire::string},      // 13
    {"last_error_utime", Wire::i64},   // 14
};

constexpr WireField fit_fields[] = {
    {"utime", Wire::i64},                // 0
    {"bench", Wire::string},             // 1
    {"run", Wire::i32},                  // 2
    {"t_cut_s", Wire::f64},              // 3
    {"t_stop_s", Wire::f64},             // 4
    {"samples", Wire::i32},              // 5
    {"inertia_kg_m2", Wire::f64},        // 6
    {"kb_v_s_per_rad", Wire::f64},       // 7
    {"bench_source", Wire::string},      // 8
    {"zero_level", Wire::f64},           // 9
    {"residual_unit", Wire::string},     // 10
    {"nmodels", Wire::i32},              // 11
    {"model", Wire::string, 11},         // 12
    {"rmse", Wire::f64, 11},             // 13
    {"r2", Wire::f64, 11},               // 14
    {"aic", Wire::f64, 11},              // 15
    {"bic", Wire::f64, 11},              // 16
    {"t_stop_pred_s", Wire::f64, 11},    // 17
    {"converged", Wire::boolean, 11},    // 18
    {"nparams", Wire::i32},              // 19
    {"param_model", Wire::i32, 19},      // 20
    {"param_name", Wire::string, 19},    // 21
    {"param_value", Wire::f64, 19},      // 22
    {"param_stderr", Wire::f64, 19},     // 23
    {"param_unit", Wire::string, 19},    // 24
    {"best", Wire::string},              // 25
    {"best_reason", Wire::string},       // 26
    {"verdict", Wire::string},           // 27
    {"verdict_reason", Wire::string},    // 28
    {"latency_s", Wire::f64},            // 29
    {"inertia_source", Wire::string},    // 30
    {"kb_source", Wire::string},         // 31
    {"lead_in", Wire::string},           // 32
    {"noise_level", Wire::f64},          // 33
    {"period_s", Wire::f64},             // 34
    {"model_samples", Wire::i32, 11},    // 35
    {"model_message", Wire::string, 11}, // 36
    {"first_seq", Wire::i64},            // 37
    {"last_seq", Wire::i64},             // 38
    {"health_reference", Wire::boolean}, // 39
    {"nfindings", Wire::i32},            // 40
    {"finding_what", Wire::string, 40},  // 41
    {"finding_level", Wire::string, 40}, // 42
    {"finding_reason", Wire::string, 40},           // 43
    {"finding_value", Wire::f64, 40},               // 44
    {"finding_stderr", Wire::f64, 40},              // 45
    {"finding_reference", Wire::f64, 40},           // 46
    {"finding_reference_stderr", Wire::f64, 40},    // 47
    {"finding_reference_name", Wire::string, 40},   // 48
    {"finding_ratio", Wire::f64, 40},               // 49
    {"finding_ratio_stderr", Wire::f64, 40},        // 50
    {"finding_unit", Wire::string, 40},             // 51
    {"t_end_s", Wire::f64},                         // 52
    {"end", Wire::string},                          // 53
    {"ndoubts", Wire::i32},                         // 54
    {"doubts", Wire::string, 54},                   // 55
    {"reading_step", Wire::f64},                    // 56
    {"model_reduced_chi2", Wire::f64, 11},          // 57
    {"ncorrelations", Wire::i32},                   // 58
    {"corr_model", Wire::i32, 58},                  // 59
    {"corr_a", Wire::string, 58},                   // 60
    {"corr_b", Wire::string, 58},                   // 61
    {"corr_value", Wire::f64, 58},                  // 62
    {"inertia_rel_error", Wire::f64},               // 63
    {"kb_rel_error", Wire::f64},                    // 64
    {"param_bench_error", Wire::f64, 19},           // 65
    {"reading_noise", Wire::f64},                   // 66
};

constexpr WireField explain_fields[] = {
    {"utime", Wire::i64},                    // 0
    {"bench", Wire::string},                 // 1
    {"run", Wire::i32},                      // 2
    {"nbase", Wire::i32},                    // 3
    {"base", Wire::string, 3},               // 4
    {"rmse_base", Wire::f64},                // 5
    {"rmse_final", Wire::f64},               // 6
    {"noise_level", Wire::f64},              // 7
    {"nsteps", Wire::i32},                   // 8
    {"step_added", Wire::string, 8},         // 9
    {"step_rmse_before", Wire::f64, 8},      // 10
    {"step_rmse_after", Wire::f64, 8},       // 11
    {"step_why", Wire::string, 8},           // 12
    {"nwhere", Wire::i32},                   // 13
    {"where_step", Wire::i32, 13},           // 14
    {"where_t_from_s", Wire::f64, 13},       // 15
    {"where_t_to_s", Wire::f64, 13},         // 16
    {"where_mean_residual", Wire::f64, 13},  // 17
    {"nfinal", Wire::i32},                   // 18
    {"final_effects", Wire::string, 18},     // 19
    {"nparams", Wire::i32},                  // 20
    {"param_name", Wire::string, 20},        // 21
    {"param_value", Wire::f64, 20},          // 22
    {"param_stderr", Wire::f64, 20},         // 23
    {"param_unit", Wire::string, 20},        // 24
    {"story", Wire::string},                 // 25
};

template <class Msg>
std::span<const WireField> layout_of();
template <>
std::span<const WireField> layout_of<samples_t>() { return samples_fields; }
template <>
std::span<const WireField> layout_of<config_t>() { return config_fields; }
template <>
std::span<const WireField> layout_of<run_t>() { return run_fields; }
template <>
std::span<const WireField> layout_of<status_t>() { return status_fields; }
template <>
std::span<const WireField> layout_of<fit_t>() { return fit_fields; }
template <>
std::span<const WireField> layout_of<explain_t>() { return explain_fields; }

template <class Msg>
bool check_impl(const void* data, std::int64_t size, std::string* why) {
  return walk(Msg::getTypeName(), static_cast<std::uint64_t>(Msg::getHash()), layout_of<Msg>(), data, size, why);
}

template <class Msg>
bool decode_impl(Msg& msg, const void* data, std::int64_t size, std::string* why) {
  if (!check_impl<Msg>(data, size, why)) return false;
  try {
    if (msg.decode(data, 0, static_cast<int>(size)) < 0)
      return fail(why, fmt::format("{}: {} bytes do not decode", Msg::getTypeName(), size));
  } catch (const std::exception& e) {  // not expected after the walk; never let it escape
    return fail(why, fmt::format("{}: does not decode ({})", Msg::getTypeName(), e.what()));
  }
  return true;
}

}  // namespace

bool view_samples_message_worded(SamplesView& view, const void* data, std::int64_t size, std::string* why) {
  const auto* d = static_cast<const unsigned char*>(data);
  if (d == nullptr || size < hash_bytes || size > std::numeric_limits<int>::max() ||
      be64u(d) != static_cast<std::uint64_t>(samples_t::getHash())) {
    check_impl<samples_t>(data, size, why);  // rejects it, in its own words
    return false;
  }
  // samples_t's strings and arrays all sit in this prefix: checking it checks the whole layout.
  if (size < 20) return fail(why, fmt::format("{} bytes, too short for samples_t", size));
  const std::int64_t bench_len = be32(d + 16);
  if (bench_len < 1 || bench_len > size - 20)
    return fail(why, fmt::format("bench string length {} does not fit in {} bytes", bench_len, size));
  const std::int64_t n_at = 20 + bench_len + 8 + 4 + 1;
  if (n_at + 4 > size) return fail(why, fmt::format("truncated: {} bytes end before the sample count", size));
  const std::int64_t n = be32(d + n_at);
  constexpr std::int64_t bytes_per_sample = 8 + 8 + 8 + 4;
  if (n < 0 || n * bytes_per_sample > size - n_at - 4)
    return fail(why, fmt::format("sample count {} does not fit in {} bytes (truncated or damaged)", n, size));
  fill_samples_view(view, d, bench_len, n_at, n);
  return true;
}

void samples_from_view(const SamplesView& view, samples_t& m) {
  m.utime = view.utime;
  m.bench.assign(view.bench);
  m.seq = view.seq;
  m.clock_epoch = view.clock_epoch;
  m.quantity = view.quantity;
  m.n = view.n;
  const auto n = static_cast<std::size_t>(view.n);
  m.device_time_us.resize(n);
  m.host_time_us.resize(n);
  m.value.resize(n);
  m.raw_adc.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    m.device_time_us[i] = view.device_time_us(static_cast<std::int32_t>(i));
    m.host_time_us[i] = static_cast<std::int64_t>(be64u(view.host_time_bytes + 8 * i));
    m.value[i] = view.value(static_cast<std::int32_t>(i));
    m.raw_adc[i] = be32(view.raw_adc_bytes + 4 * i);
  }
}

#define SPINDOWN_DEFINE_MESSAGE_DECODE(T)                                                      \
  template <>                                                                                  \
  bool check_message_encoding<T>(const void* data, std::int64_t size, std::string* why) {      \
    return check_impl<T>(data, size, why);                                                     \
  }                                                                                            \
  template <>                                                                                  \
  bool decode_message<T>(T & msg, const void* data, std::int64_t size, std::string* why) {     \
    return decode_impl<T>(msg, data, size, why);                                               \
  }
SPINDOWN_DEFINE_MESSAGE_DECODE(samples_t)
SPINDOWN_DEFINE_MESSAGE_DECODE(config_t)
SPINDOWN_DEFINE_MESSAGE_DECODE(run_t)
SPINDOWN_DEFINE_MESSAGE_DECODE(fit_t)
SPINDOWN_DEFINE_MESSAGE_DECODE(explain_t)
SPINDOWN_DEFINE_MESSAGE_DECODE(status_t)
#undef SPINDOWN_DEFINE_MESSAGE_DECODE

}  // namespace spindown
