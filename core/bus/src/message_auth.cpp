#include "spindown/message_auth.hpp"

#include <array>
#include <fmt/format.h>
#include <sodium.h>

namespace spindown {

namespace {

static_assert(crypto_auth_BYTES == message_auth_bytes, "auth[32] holds one crypto_auth tag");
static_assert(crypto_auth_KEYBYTES == lab_key_bytes, "a lab key is one crypto_auth key");

// crypto_auth (HMAC-SHA512-256) of channel, NUL, bytes[0, auth_offset), 32 zero bytes, the rest.
void compute_tag(std::string_view channel, const unsigned char* bytes, std::int64_t size, std::int64_t auth_offset,
                 const LabKey& key, unsigned char* tag) {
  static const bool ready = ::sodium_init() >= 0;
  (void)ready;
  crypto_auth_hmacsha512256_state st;
  crypto_auth_hmacsha512256_init(&st, key.bytes.data(), key.bytes.size());
  crypto_auth_hmacsha512256_update(&st, reinterpret_cast<const unsigned char*>(channel.data()), channel.size());
  const unsigned char nul = 0;
  crypto_auth_hmacsha512256_update(&st, &nul, 1);
  crypto_auth_hmacsha512256_update(&st, bytes, static_cast<unsigned long long>(auth_offset));
  const std::array<unsigned char, message_auth_bytes> zeros{};
  crypto_auth_hmacsha512256_update(&st, zeros.data(), zeros.size());
  const std::int64_t after = auth_offset + message_auth_bytes;
  crypto_auth_hmacsha512256_update(&st, bytes + after, static_cast<unsigned long long>(size - after));
  crypto_auth_hmacsha512256_final(&st, tag);
  ::sodium_memzero(&st, sizeof st);
}

// The trailer of a whole message of the current encoding; false and *why otherwise.
bool whole_message(const void* data, std::int64_t size, MessageTrailer& t, std::string* why) {
  if (!read_message_trailer(data, size, t, why)) return false;
  if (t.legacy) return true;  // no signature fields: "not signed"
  if (t.end != size) {
    if (why) *why = fmt::format("{}: {} bytes after the end of the message", t.type, size - t.end);
    return false;
  }
  return true;
}

}  // namespace

bool sign_encoded_message(std::string_view channel, std::span<unsigned char> bytes, const LabKey& key, std::string* why) {
  MessageTrailer t;
  const auto size = static_cast<std::int64_t>(bytes.size());
  if (!whole_message(bytes.data(), size, t, why)) return false;
  if (t.legacy) {
    if (why) *why = fmt::format("{}: an encoding without signature fields (older type)", t.type);
    return false;
  }
  const auto id = static_cast<std::uint32_t>(key.id);
  unsigned char* id_at = bytes.data() + t.auth_offset - 4;
  id_at[0] = static_cast<unsigned char>(id >> 24);
  id_at[1] = static_cast<unsigned char>(id >> 16);
  id_at[2] = static_cast<unsigned char>(id >> 8);
  id_at[3] = static_cast<unsigned char>(id);
  compute_tag(channel, bytes.data(), size, t.auth_offset, key, bytes.data() + t.auth_offset);
  return true;
}

std::string_view auth_status_name(AuthStatus s) {
  switch (s) {
    case AuthStatus::valid: return "valid";
    case AuthStatus::not_signed: return "not signed";
    case AuthStatus::other_key: return "other key";
    case AuthStatus::bad_signature: return "bad signature";
    case AuthStatus::malformed: return "malformed";
  }
  return "?";
}

AuthCheck verify_message(std::string_view channel, const void* data, std::int64_t size, const LabKey& key) {
  AuthCheck c;
  if (!whole_message(data, size, c.trailer, &c.why)) {
    c.status = AuthStatus::malformed;
    return c;
  }
  if (c.trailer.legacy || c.trailer.auth_key_id == 0) {
    c.status = AuthStatus::not_signed;
    return c;
  }
  if (c.trailer.auth_key_id != key.id) {
    c.status = AuthStatus::other_key;
    return c;
  }
  std::array<unsigned char, message_auth_bytes> tag{};
  compute_tag(channel, static_cast<const unsigned char*>(data), size, c.trailer.auth_offset, key, tag.data());
  c.status = ::crypto_verify_32(tag.data(), c.trailer.auth) == 0 ? AuthStatus::valid : AuthStatus::bad_signature;
  return c;
}

}  // namespace spindown
