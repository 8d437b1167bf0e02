#pragma once
// Decoding a spindown LCM message from untrusted bytes. lcm-gen's decoders (LCM 1.3.1) resize
// every variable-length array to the count read from the wire before checking that the bytes
// are there, so a 100-byte message claiming nmodels = 2^31 − 1 asks for tens of gigabytes, and
// a string length of INT_MIN overflows a signed int inside the generated header. decode_message
// first walks the encoding (fingerprint, every string length, every array count against the
// bytes left) and only then runs the generated decoder, so nothing it is given can make it
// allocate more than a small multiple of the message's size, throw or hit undefined behaviour.
#include <cstdint>
#include <string>

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
