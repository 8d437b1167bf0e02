#pragma once
// Decoding a spindown LCM message from untrusted bytes. lcm-gen's decoders (LCM 1.3.1) resize
// every variable-length array to the count read from the wire before checking that the bytes
// are there, so a 100-byte message claiming nmodels = 2^31 − 1 asks for tens of gigabytes, and
// a string length of INT_MIN overflows a signed int inside the generated header. decode_message
// first walks the encoding (fingerprint, every string length, every array count against the
// bytes left) and only then runs the generated decoder, so nothing it is given can make it
// allocate more than a small multiple of the message's size, throw or hit undefined behaviour.
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>

#include <spindown/config_t.hpp>
#include <spindown/explain_t.hpp>
#include <spindown/fit_t.hpp>
#include <spindown/run_t.hpp>
#include <spindown/samples_t.hpp>
#include <spindown/status_t.hpp>

namespace spindown {

// Checks the structure of an encoded message of type Msg (size bytes at data, fingerprint
// first). True when the generated decoder can read it safely; otherwise false and *why says
// what is wrong ("fit_t: nmodels = 2147483647 needs at least … bytes, 61 left at byte 95").
template <class Msg>
bool check_message_encoding(const void* data, std::int64_t size, std::string* why = nullptr);

// check_message_encoding, then the generated decoder. False and *why when the bytes are not a
// well-formed Msg; msg is then unspecified (but valid).
// Both also take a type's encoding from before issue 31 appended the source and signature fields
// (its older fingerprint: logs written until then): msg then has those fields empty.
template <class Msg>
bool decode_message(Msg& msg, const void* data, std::int64_t size, std::string* why = nullptr);

// Every type ends with the same seven fields (lcmtypes/*.lcm): lab, sent_to, source_host,
// source_session, source_seq, auth_key_id and auth[32].
inline constexpr std::int64_t message_auth_bytes = 32;

// Those fields read in place from a message's bytes, for any of spindown's types (found by its
// fingerprint). Valid while the bytes are.
struct MessageTrailer {
  std::string_view type;          // "samples_t", …
  bool legacy = false;            // an encoding from before the fields existed: they read empty
  std::int64_t utime = 0;         // the message's first field
  std::string_view lab, sent_to, source_host;
  std::uint64_t source_session = 0;
  std::int64_t source_seq = 0;
  std::int32_t auth_key_id = 0;
  const unsigned char* auth = nullptr;  // message_auth_bytes bytes (nullptr when legacy)
  std::int64_t auth_offset = 0;         // byte offset of auth in the message
  std::int64_t end = 0;                 // where the encoding ends (== the size for a whole message)
};
// False and *why when the bytes are not a well-formed spindown message of any type.
bool read_message_trailer(const void* data, std::int64_t size, MessageTrailer& out, std::string* why = nullptr);

// A samples_t read in place from its encoding (the message the lab bridge sends once per
// sample): no vectors or strings are built, the arrays are read from the big-endian bytes. Valid
// while those bytes are.
struct SamplesView {
  std::int64_t utime = 0;
  std::string_view bench;
  std::int64_t seq = 0;
  std::int32_t clock_epoch = 0;
  std::int8_t quantity = 0;
  std::int32_t n = 0;
  // The four arrays, n big-endian values each: int64, int64, IEEE double, int32.
  const unsigned char* device_time_bytes = nullptr;
  const unsigned char* host_time_bytes = nullptr;
  const unsigned char* value_bytes = nullptr;
  const unsigned char* raw_adc_bytes = nullptr;
  // The source fields (MessageTrailer's); empty for a message from before they existed (legacy).
  bool legacy = false;
  std::string_view lab, sent_to, source_host;
  std::uint64_t source_session = 0;
  std::int64_t source_seq = 0;
  std::int32_t auth_key_id = 0;
  const unsigned char* auth = nullptr;  // message_auth_bytes bytes, nullptr when legacy

  std::int64_t device_time_us(std::int32_t i) const {
    return static_cast<std::int64_t>(load_be64(device_time_bytes + 8 * static_cast<std::size_t>(i)));
  }
  double value(std::int32_t i) const {
    return std::bit_cast<double>(load_be64(value_bytes + 8 * static_cast<std::size_t>(i)));
  }
  static std::uint64_t load_be64(const unsigned char* p) {
    std::uint64_t v;
    std::memcpy(&v, p, sizeof v);
    if constexpr (std::endian::native == std::endian::little) v = __builtin_bswap64(v);
    return v;
  }
  static std::int32_t load_be32(const unsigned char* p) {
    std::uint32_t v;
    std::memcpy(&v, p, sizeof v);
    if constexpr (std::endian::native == std::endian::little) v = __builtin_bswap32(v);
    return static_cast<std::int32_t>(v);
  }
};

// Checks an encoded samples_t (fingerprint, bench length, sample count against the bytes there)
// and points view at it. False and *why otherwise, with the words the log reader and the fitter
// report ("sample count 57 does not fit in 1445 bytes (truncated or damaged)"); a wrong
// fingerprint or a message shorter than one is worded as decode_message words it.
// Always inlined, as a reader makes it once per message (a call costs as much as the checks): a
// sound message passes the checks here; any other is handed to view_samples_message_worded,
// which checks again and says what is wrong.
inline bool view_samples_message(SamplesView& view, const void* data, std::int64_t size, std::string* why = nullptr);

// view_samples_message step by step, each failed check in words (out of line: the rare path).
bool view_samples_message_worded(SamplesView& view, const void* data, std::int64_t size, std::string* why);

// samples_t::getHash() read once: the generated function guards a local static on every call.
inline const std::uint64_t samples_fingerprint = static_cast<std::uint64_t>(samples_t::getHash());

// The whole samples_t from a view (for readers that hand on the generated type); m's vectors
// keep their capacity.
void samples_from_view(const SamplesView& view, samples_t& m);

// The view's fields from a samples_t encoding d whose layout is checked: a bench string of
// bench_len bytes (its NUL included), n samples from byte n_at + 4, then (unless legacy) the
// trailer: lab (lab_len bytes with its NUL) at trailer_at + 4, sent_to (to_len) and source_host
// (host_len) after it.
inline void fill_samples_view(SamplesView& view, const unsigned char* d, std::int64_t bench_len, std::int64_t n_at,
                              std::int64_t n, std::int64_t trailer_at, std::int64_t lab_len, std::int64_t to_len,
                              std::int64_t host_len) {
  view.utime = static_cast<std::int64_t>(SamplesView::load_be64(d + 8));
  view.bench = std::string_view(reinterpret_cast<const char*>(d + 20), static_cast<std::size_t>(bench_len - 1));
  const unsigned char* p = d + 20 + bench_len;
  view.seq = static_cast<std::int64_t>(SamplesView::load_be64(p));
  view.clock_epoch = SamplesView::load_be32(p + 8);
  view.quantity = static_cast<std::int8_t>(p[12]);
  view.n = static_cast<std::int32_t>(n);
  view.device_time_bytes = d + n_at + 4;
  view.host_time_bytes = view.device_time_bytes + 8 * n;
  view.value_bytes = view.host_time_bytes + 8 * n;
  view.raw_adc_bytes = view.value_bytes + 8 * n;
  view.legacy = trailer_at < 0;
  if (view.legacy) {
    view.lab = view.sent_to = view.source_host = {};
    view.source_session = 0;
    view.source_seq = 0;
    view.auth_key_id = 0;
    view.auth = nullptr;
    return;
  }
  const auto* lab = d + trailer_at + 4;
  view.lab = std::string_view(reinterpret_cast<const char*>(lab), static_cast<std::size_t>(lab_len - 1));
  const auto* to = lab + lab_len + 4;
  view.sent_to = std::string_view(reinterpret_cast<const char*>(to), static_cast<std::size_t>(to_len - 1));
  const auto* host = to + to_len + 4;
  view.source_host = std::string_view(reinterpret_cast<const char*>(host), static_cast<std::size_t>(host_len - 1));
  const auto* after = host + host_len;
  view.source_session = SamplesView::load_be64(after);
  view.source_seq = static_cast<std::int64_t>(SamplesView::load_be64(after + 8));
  view.auth_key_id = SamplesView::load_be32(after + 16);
  view.auth = after + 20;
}

[[gnu::always_inline]] inline bool view_samples_message(SamplesView& view, const void* data, std::int64_t size,
                                                      std::string* why) {
  // Fingerprint, utime and the bench string's length take the first 20 bytes; after the bench
  // come seq, clock_epoch, quantity (13 bytes) and n, then n samples of 8 + 8 + 8 + 4 bytes, then
  // the trailer: lab, sent_to and source_host (strings), source_session, source_seq, auth_key_id, auth.
  constexpr std::int64_t bytes_per_sample = 8 + 8 + 8 + 4;
  constexpr std::int64_t trailer_fixed = 8 + 8 + 4 + message_auth_bytes;
  const auto* d = static_cast<const unsigned char*>(data);
  if (d == nullptr || size < 20 || size > std::numeric_limits<int>::max() ||
      SamplesView::load_be64(d) != samples_fingerprint)
    return view_samples_message_worded(view, data, size, why);
  const std::int64_t bench_len = SamplesView::load_be32(d + 16);
  if (bench_len < 1 || bench_len > size - 20) return view_samples_message_worded(view, data, size, why);
  const std::int64_t n_at = 20 + bench_len + 13;
  if (n_at + 4 > size) return view_samples_message_worded(view, data, size, why);
  const std::int64_t n = SamplesView::load_be32(d + n_at);
  if (n < 0 || n * bytes_per_sample > size - n_at - 4) return view_samples_message_worded(view, data, size, why);
  const std::int64_t trailer_at = n_at + 4 + n * bytes_per_sample;
  if (trailer_at + 4 > size) return view_samples_message_worded(view, data, size, why);
  const std::int64_t lab_len = SamplesView::load_be32(d + trailer_at);
  if (lab_len < 1 || lab_len > size - trailer_at - 8) return view_samples_message_worded(view, data, size, why);
  const std::int64_t to_at = trailer_at + 4 + lab_len;
  const std::int64_t to_len = SamplesView::load_be32(d + to_at);
  if (to_len < 1 || to_len > size - to_at - 8) return view_samples_message_worded(view, data, size, why);
  const std::int64_t host_at = to_at + 4 + to_len;
  const std::int64_t host_len = SamplesView::load_be32(d + host_at);
  if (host_len < 1 || host_len > size - host_at - 4 - trailer_fixed) return view_samples_message_worded(view, data, size, why);
  fill_samples_view(view, d, bench_len, n_at, n, trailer_at, lab_len, to_len, host_len);
  return true;
}

#define SPINDOWN_DECLARE_MESSAGE_DECODE(T)                                                        \
  template <>                                                                                     \
  bool check_message_encoding<T>(const void* data, std::int64_t size, std::string* why);          \
  template <>                                                                                     \
  bool decode_message<T>(T & msg, const void* data, std::int64_t size, std::string* why);
SPINDOWN_DECLARE_MESSAGE_DECODE(samples_t)
SPINDOWN_DECLARE_MESSAGE_DECODE(config_t)
SPINDOWN_DECLARE_MESSAGE_DECODE(run_t)
SPINDOWN_DECLARE_MESSAGE_DECODE(fit_t)
SPINDOWN_DECLARE_MESSAGE_DECODE(explain_t)
SPINDOWN_DECLARE_MESSAGE_DECODE(status_t)
#undef SPINDOWN_DECLARE_MESSAGE_DECODE

}  // namespace spindown
