#pragma once
// Signed messages (issue 31; docs/security.md). Every spindown type ends with auth_key_id and
// auth[32] (lcmtypes/*.lcm); a signed message carries the lab key's id and
//   auth = crypto_auth(channel name, a NUL byte, the encoded message with auth zeroed)
// — libsodium's crypto_auth is HMAC-SHA512-256 — so the signature covers every field, the type's
// fingerprint and the channel it was sent on. One function signs and one verifies, for every
// type, on the encoded bytes: what LCM carries and what a log holds.
//
// These two are the library's verification for any program (the fitter, the logger, refit,
// watch, and a web service): verify_message() says what a message is; MessageGate
// (message_gate.hpp) adds the lab, the replay window and the counts.
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "spindown/lab_key.hpp"
#include "spindown/message_decode.hpp"

namespace spindown {

// Signs an encoded message in place: sets auth_key_id and auth. False and *why when the bytes
// are not one whole spindown message of the current encoding.
bool sign_encoded_message(std::string_view channel, std::span<unsigned char> bytes, const LabKey& key,
                          std::string* why = nullptr);

enum class AuthStatus {
  valid,          // signed with this key, and the signature matches
  not_signed,     // auth_key_id 0 (or a message from before signatures existed)
  other_key,      // signed with a key whose id is not this key's
  bad_signature,  // this key's id, but the signature does not match: forged, or changed on the way
  malformed,      // not a whole spindown message (trailing bytes, damage): cannot be checked
};
std::string_view auth_status_name(AuthStatus s);  // "valid", "not signed", "other key", …

struct AuthCheck {
  AuthStatus status = AuthStatus::malformed;
  MessageTrailer trailer;  // its source fields (valid when status is not malformed)
  std::string why;         // for malformed: what is wrong
};

// What a received message is, against key. Constant time in the signature's comparison.
AuthCheck verify_message(std::string_view channel, const void* data, std::int64_t size, const LabKey& key);

}  // namespace spindown
