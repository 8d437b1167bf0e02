#include "spindown/message_decode.hpp"

#include <array>
#include <bit>
#include <cstddef>
#include <cstring>
#include <exception>
#include <fmt/format.h>
#include <limits>
#include <span>
#include <string_view>
#include <vector>

#include "spindown/fail_why.hpp"

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
  int fixed = 0;      // > 0: a fixed-size array of this many (byte auth[32])
};

// The seven fields that end every type (lcmtypes/*.lcm: who sent it and its signature).
#define SPINDOWN_TRAILER_FIELDS                                                                     \
  {"lab", Wire::string}, {"sent_to", Wire::string}, {"source_host", Wire::string},                  \
      {"source_session", Wire::i64}, {"source_seq", Wire::i64}, {"auth_key_id", Wire::i32},         \
      {"auth", Wire::i8, -1, message_auth_bytes}
constexpr std::size_t trailer_field_count = 7;

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

constexpr std::size_t max_fields = 96;

// Offsets of a walk: each field's, then the end of the last one.
using Positions = std::array<std::int64_t, max_fields + 1>;

// Walks the encoding field by field; positions, when given, receives each field's byte offset and
// then the end of the last one (at index fields.size()).
bool walk(std::string_view type, std::uint64_t expected_hash, std::span<const WireField> fields,
          const void* data, std::int64_t size, std::string* why, Positions* positions = nullptr) {
  if (data == nullptr && size != 0) return fail_why(why, fmt::format("{}: no data", type));
  if (size < hash_bytes) return fail_why(why, fmt::format("{} bytes, too short for {}", size, type));
  if (size > std::numeric_limits<int>::max())
    return fail_why(why, fmt::format("{}: {} bytes, more than an LCM message can hold", type, size));
  const auto* d = static_cast<const unsigned char*>(data);
  const std::uint64_t hash = be64u(d);
  if (hash != expected_hash)
    return fail_why(why, fmt::format("not a {} (type fingerprint {:#018x}, expected {:#018x})", type, hash,
                                     expected_hash));

  std::array<std::int64_t, max_fields> ints{};  // int32 scalars by field index (array counts)
  std::int64_t pos = hash_bytes;
  for (std::size_t i = 0; i < fields.size(); ++i) {
    const WireField& f = fields[i];
    if (positions) (*positions)[i] = pos;
    std::int64_t n = f.fixed > 0 ? f.fixed : 1;
    if (f.count_of >= 0) {
      n = ints[static_cast<std::size_t>(f.count_of)];
      if (n < 0)
        return fail_why(why, fmt::format("{}: {} = {} is negative (array {})", type, fields[f.count_of].name, n,
                                         f.name));
    }
    const std::int64_t left = size - pos;
    if (f.wire != Wire::string) {
      const std::int64_t need = n * fixed_bytes(f.wire);
      if (need > left) {
        if (f.count_of >= 0)
          return fail_why(why, fmt::format("{}: {} = {} needs {} bytes for {}, {} left at byte {} (truncated or "
                                           "damaged)",
                                           type, fields[f.count_of].name, n, need, f.name, left, pos));
        return fail_why(why, fmt::format("{}: ends inside {} at byte {} (truncated)", type, f.name, pos));
      }
      if (f.wire == Wire::i32 && f.count_of < 0) ints[i] = be32(d + pos);
      pos += need;
      continue;
    }
    // Strings: a big-endian int32 length that counts the NUL, then the bytes.
    if (f.count_of < 0 && left < string_min_bytes)
      return fail_why(why, fmt::format("{}: ends inside {} at byte {} (truncated)", type, f.name, pos));
    if (n * string_min_bytes > left)
      return fail_why(why, fmt::format("{}: {} = {} strings for {} need at least {} bytes, {} left at byte {} "
                                       "(truncated or damaged)",
                                       type, fields[f.count_of].name, n, f.name, n * string_min_bytes, left, pos));
    for (std::int64_t k = 0; k < n; ++k) {
      auto name = [&] { return f.count_of >= 0 ? fmt::format("{}[{}]", f.name, k) : std::string(f.name); };
      if (size - pos < 4)
        return fail_why(why, fmt::format("{}: ends inside {} at byte {} (truncated)", type, name(), pos));
      const std::int64_t len = be32(d + pos);
      pos += 4;
      if (len < 1 || len > size - pos)
        return fail_why(why, fmt::format("{}: string {} has length {} with {} bytes left at byte {} (truncated or "
                                         "damaged)",
                                         type, name(), len, size - pos, pos - 4));
      pos += len;
    }
  }
  if (positions) (*positions)[fields.size()] = pos;
  return true;
}

constexpr WireField samples_fields[] = {
    {"utime", Wire::i64},        {"bench", Wire::string},          {"seq", Wire::i64},
    {"clock_epoch", Wire::i32},  {"quantity", Wire::i8},           {"n", Wire::i32},
    {"device_time_us", Wire::i64, 5}, {"host_time_us", Wire::i64, 5}, {"value", Wire::f64, 5},
    {"raw_adc", Wire::i32, 5},
    SPINDOWN_TRAILER_FIELDS,
};

constexpr WireField config_fields[] = {
    {"utime", Wire::i64},           {"bench", Wire::string},        {"inertia_kg_m2", Wire::f64},
    {"inertia_source", Wire::string}, {"kb_v_s_per_rad", Wire::f64}, {"kb_source", Wire::string},
    {"quantity", Wire::i8},         {"adc_volts_per_count", Wire::f64}, {"adc_bits", Wire::i32},
    {"firmware", Wire::string},     {"protocol", Wire::string},     {"sample_period_s", Wire::f64},
    {"baud", Wire::i32},            {"device", Wire::string},       {"host", Wire::string},
    {"inertia_rel_error", Wire::f64}, {"kb_rel_error", Wire::f64},
    SPINDOWN_TRAILER_FIELDS,
};

constexpr WireField run_fields[] = {
    {"utime", Wire::i64},     {"bench", Wire::string},  {"run", Wire::i32},      {"state", Wire::i8},
    {"t_cut_s", Wire::f64},   {"t_stop_s", Wire::f64},  {"first_seq", Wire::i64}, {"last_seq", Wire::i64},
    {"samples", Wire::i32},   {"note", Wire::string},   {"lead_in", Wire::string},
    {"bridge_host", Wire::string},  {"bridge_session", Wire::i64},
    SPINDOWN_TRAILER_FIELDS,
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
    {"start_utime", Wire::i64},        // 15
    SPINDOWN_TRAILER_FIELDS,
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
    {"bridge_host", Wire::string},                  // 67
    {"bridge_session", Wire::i64},                  // 68
    SPINDOWN_TRAILER_FIELDS,
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
    SPINDOWN_TRAILER_FIELDS,
};

// Each type: its layout, and the fingerprint and field count of its encoding before issue 31
// appended the source and signature fields (what spindown wrote until then: those logs still
// read, their messages with the new fields empty).
struct TypeInfo {
  std::string_view name;
  std::uint64_t hash;
  std::span<const WireField> fields;
  std::uint64_t legacy_hash;
  std::size_t legacy_fields;
};

template <class Msg>
const TypeInfo& type_info();
#define SPINDOWN_TYPE_INFO(T, layout, old_hash, old_fields)                                          \
  template <>                                                                                      \
  const TypeInfo& type_info<T>() {                                                                 \
    static_assert(std::size(layout) <= max_fields);                                                \
    static const TypeInfo info{T::getTypeName(), static_cast<std::uint64_t>(T::getHash()), layout, \
                               old_hash, old_fields};                                              \
    return info;                                                                                   \
  }
SPINDOWN_TYPE_INFO(samples_t, samples_fields, 0x6366464c24ab26e1ull, 10)
SPINDOWN_TYPE_INFO(config_t, config_fields, 0xf33bcecf4e9c80bdull, 17)
SPINDOWN_TYPE_INFO(run_t, run_fields, 0x52fa3d633257d3efull, 11)
SPINDOWN_TYPE_INFO(fit_t, fit_fields, 0x9a6ae2b7c7c8e61cull, 67)
SPINDOWN_TYPE_INFO(explain_t, explain_fields, 0x8e7064d4b8398716ull, 26)
SPINDOWN_TYPE_INFO(status_t, status_fields, 0x056ac82d6252dc21ull, 15)
#undef SPINDOWN_TYPE_INFO

const TypeInfo* type_of_hash(std::uint64_t hash, bool* legacy) {
  for (const TypeInfo* t : {&type_info<samples_t>(), &type_info<config_t>(), &type_info<run_t>(),
                            &type_info<fit_t>(), &type_info<explain_t>(), &type_info<status_t>()}) {
    if (hash == t->hash || hash == t->legacy_hash) {
      *legacy = hash == t->legacy_hash;
      return t;
    }
  }
  return nullptr;
}

std::uint64_t hash_of(const void* data, std::int64_t size) {
  return data != nullptr && size >= hash_bytes ? be64u(static_cast<const unsigned char*>(data)) : 0;
}

// The walk of either encoding of a type: the legacy one is the current layout without the
// appended fields. legacy tells which it was.
bool walk_type(const TypeInfo& t, const void* data, std::int64_t size, std::string* why, bool* legacy,
               Positions* positions = nullptr) {
  // The fingerprint is read only from a size walk() takes (a size beyond an LCM message is refused
  // there, before any byte is read).
  *legacy = size >= hash_bytes && size <= std::numeric_limits<int>::max() && data != nullptr &&
            hash_of(data, size) == t.legacy_hash;
  if (*legacy) return walk(t.name, t.legacy_hash, t.fields.first(t.legacy_fields), data, size, why, positions);
  return walk(t.name, t.hash, t.fields, data, size, why, positions);
}

// The encoding of a field the legacy encoding lacks, at its default (all appended fields are
// scalars or fixed arrays): "" for a string, zeros otherwise.
void append_default(std::vector<unsigned char>& out, const WireField& f) {
  if (f.wire == Wire::string) {
    const unsigned char empty[5] = {0, 0, 0, 1, 0};
    out.insert(out.end(), empty, empty + 5);
    return;
  }
  out.insert(out.end(), static_cast<std::size_t>(fixed_bytes(f.wire) * (f.fixed > 0 ? f.fixed : 1)), 0);
}

template <class Msg>
bool check_impl(const void* data, std::int64_t size, std::string* why) {
  bool legacy = false;
  return walk_type(type_info<Msg>(), data, size, why, &legacy);
}

template <class Msg>
bool decode_impl(Msg& msg, const void* data, std::int64_t size, std::string* why) {
  const TypeInfo& t = type_info<Msg>();
  bool legacy = false;
  Positions positions;
  if (!walk_type(t, data, size, why, &legacy, &positions)) return false;
  std::vector<unsigned char> upgraded;
  if (legacy) {  // the current encoding of the same message: its fields, then the new ones empty
    const auto* d = static_cast<const unsigned char*>(data);
    const std::int64_t end = positions[t.legacy_fields];
    upgraded.reserve(static_cast<std::size_t>(end) + 128);
    for (int k = 56; k >= 0; k -= 8) upgraded.push_back(static_cast<unsigned char>(t.hash >> k));
    upgraded.insert(upgraded.end(), d + hash_bytes, d + end);
    for (std::size_t i = t.legacy_fields; i < t.fields.size(); ++i) append_default(upgraded, t.fields[i]);
    data = upgraded.data();
    size = static_cast<std::int64_t>(upgraded.size());
  }
  try {
    if (msg.decode(data, 0, static_cast<int>(size)) < 0)
      return fail_why(why, fmt::format("{}: {} bytes do not decode", Msg::getTypeName(), size));
  } catch (const std::exception& e) {  // not expected after the walk; never let it escape
    return fail_why(why, fmt::format("{}: does not decode ({})", Msg::getTypeName(), e.what()));
  }
  return true;
}

}  // namespace

bool view_samples_message_worded(SamplesView& view, const void* data, std::int64_t size, std::string* why) {
  const auto* d = static_cast<const unsigned char*>(data);
  const TypeInfo& t = type_info<samples_t>();
  const bool legacy = d != nullptr && size >= hash_bytes && be64u(d) == t.legacy_hash;
  if (d == nullptr || size < hash_bytes || size > std::numeric_limits<int>::max() ||
      (be64u(d) != t.hash && !legacy)) {
    check_impl<samples_t>(data, size, why);  // rejects it, in its own words
    return false;
  }
  // samples_t's strings and arrays all sit in this prefix: checking it checks the whole layout.
  if (size < 20) return fail_why(why, fmt::format("{} bytes, too short for samples_t", size));
  const std::int64_t bench_len = be32(d + 16);
  if (bench_len < 1 || bench_len > size - 20)
    return fail_why(why, fmt::format("bench string length {} does not fit in {} bytes", bench_len, size));
  const std::int64_t n_at = 20 + bench_len + 8 + 4 + 1;
  if (n_at + 4 > size) return fail_why(why, fmt::format("truncated: {} bytes end before the sample count", size));
  const std::int64_t n = be32(d + n_at);
  constexpr std::int64_t bytes_per_sample = 8 + 8 + 8 + 4;
  if (n < 0 || n * bytes_per_sample > size - n_at - 4)
    return fail_why(why, fmt::format("sample count {} does not fit in {} bytes (truncated or damaged)", n, size));
  const std::int64_t trailer_at = n_at + 4 + n * bytes_per_sample;
  if (legacy) {
    fill_samples_view(view, d, bench_len, n_at, n, -1, 0, 0, 0);
    return true;
  }
  if (trailer_at + 4 > size)
    return fail_why(why, fmt::format("truncated: {} bytes end before the source fields (lab, host, session)", size));
  const std::int64_t lab_len = be32(d + trailer_at);
  if (lab_len < 1 || lab_len > size - trailer_at - 8)
    return fail_why(why, fmt::format("lab string length {} does not fit in {} bytes", lab_len, size));
  const std::int64_t to_at = trailer_at + 4 + lab_len;
  const std::int64_t to_len = be32(d + to_at);
  if (to_len < 1 || to_len > size - to_at - 8)
    return fail_why(why, fmt::format("sent_to string length {} does not fit in {} bytes", to_len, size));
  const std::int64_t host_at = to_at + 4 + to_len;
  const std::int64_t host_len = be32(d + host_at);
  constexpr std::int64_t trailer_fixed = 8 + 8 + 4 + message_auth_bytes;
  if (host_len < 1 || host_len > size - host_at - 4 - trailer_fixed)
    return fail_why(why, fmt::format("source_host string length {} does not fit in {} bytes (truncated or damaged)",
                                     host_len, size));
  fill_samples_view(view, d, bench_len, n_at, n, trailer_at, lab_len, to_len, host_len);
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
  m.lab.assign(view.lab);
  m.sent_to.assign(view.sent_to);
  m.source_host.assign(view.source_host);
  m.source_session = static_cast<std::int64_t>(view.source_session);
  m.source_seq = view.source_seq;
  m.auth_key_id = view.auth_key_id;
  if (view.auth)
    std::memcpy(m.auth, view.auth, sizeof m.auth);
  else
    std::memset(m.auth, 0, sizeof m.auth);
}

bool read_message_trailer(const void* data, std::int64_t size, MessageTrailer& out, std::string* why) {
  out = MessageTrailer{};
  if (data == nullptr || size < hash_bytes)
    return fail_why(why, fmt::format("{} bytes, too short for a spindown message", std::max<std::int64_t>(size, 0)));
  bool legacy = false;
  const TypeInfo* t = type_of_hash(hash_of(data, size), &legacy);
  if (!t)
    return fail_why(why, fmt::format("not a spindown message (type fingerprint {:#018x})", hash_of(data, size)));
  Positions at;  // each field's offset, then the end
  if (!walk_type(*t, data, size, why, &legacy, &at)) return false;
  const auto* d = static_cast<const unsigned char*>(data);
  out.type = t->name;
  out.legacy = legacy;
  out.end = at[legacy ? t->legacy_fields : t->fields.size()];
  out.utime = static_cast<std::int64_t>(be64u(d + hash_bytes));  // every type starts with utime
  if (legacy) return true;
  const std::size_t first = t->fields.size() - trailer_field_count;
  auto string_at = [&](std::size_t field) {
    const std::int64_t p = at[field];
    return std::string_view(reinterpret_cast<const char*>(d + p + 4), static_cast<std::size_t>(be32(d + p) - 1));
  };
  out.lab = string_at(first);
  out.sent_to = string_at(first + 1);
  out.source_host = string_at(first + 2);
  out.source_session = be64u(d + at[first + 3]);
  out.source_seq = static_cast<std::int64_t>(be64u(d + at[first + 4]));
  out.auth_key_id = be32(d + at[first + 5]);
  out.auth_offset = at[first + 6];
  out.auth = d + out.auth_offset;
  return true;
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
