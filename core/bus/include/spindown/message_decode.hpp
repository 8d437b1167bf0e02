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
template <class Msg>
bool decode_message(Msg& msg, const void* data, std::int64_t size, std::string* why = nullptr);

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
// bench_len bytes (its NUL included) and n samples from byte n_at + 4.
inline void fill_samples_view(SamplesView& view, const unsigned char* d, std::int64_t bench_len, std::int64_t n_at,
                              std::int64_t n) {
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
}

[[gnu::always_inline]] inline bool view_samples_message(SamplesView& view, const void* data, std::int64_t size,
                                                      std::string* why) {
  // Fingerprint, utime and the bench string's length take the first 20 bytes; after the bench
  // come seq, clock_epoch, quantity (13 bytes) and n, then n samples of 8 + 8 + 8 + 4 bytes.
  constexpr std::int64_t bytes_per_sample = 8 + 8 + 8 + 4;
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
  fill_samples_view(view, d, bench_len, n_at, n);
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
