// Signed messages: one function signs and one verifies every type, on the encoded bytes; any
// change to a signed message (any byte, the channel it is sent on, another key) is caught.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "spindown/lab_key.hpp"
#include "spindown/message_auth.hpp"
#include "spindown_messages.hpp"

namespace spindown {
namespace {

using namespace spindown::test;

LabKey key_of(unsigned char fill) {
  std::array<unsigned char, lab_key_bytes> b{};
  b.fill(fill);
  b[0] = 1;
  return lab_key_from_bytes(b);
}

template <class Msg>
void every_change_is_caught(const Msg& m) {
  const LabKey key = key_of(7);
  const std::string channel = "SPINDOWN.bench-a.X";
  auto bytes = encoded(m);
  const auto size = static_cast<std::int64_t>(bytes.size());
  EXPECT_EQ(verify_message(channel, bytes.data(), size, key).status, AuthStatus::not_signed) << Msg::getTypeName();
  std::string why;
  ASSERT_TRUE(sign_encoded_message(channel, bytes, key, &why)) << why;
  const AuthCheck ok = verify_message(channel, bytes.data(), size, key);
  ASSERT_EQ(ok.status, AuthStatus::valid) << Msg::getTypeName();
  EXPECT_EQ(ok.trailer.auth_key_id, key.id);
  EXPECT_EQ(ok.trailer.source_session, 0x1234abcd5678ef01u);
  // The signed bytes decode as the message (the key id and tag set, nothing else changed).
  Msg back{};
  ASSERT_TRUE(decode_message(back, bytes.data(), size, &why)) << why;
  EXPECT_EQ(back.auth_key_id, key.id);
  back.auth_key_id = 0;
  std::memset(back.auth, 0, sizeof back.auth);
  EXPECT_EQ(encoded(back), encoded(m));

  EXPECT_EQ(verify_message("SPINDOWN.bench-b.X", bytes.data(), size, key).status, AuthStatus::bad_signature)
      << "another channel";
  EXPECT_EQ(verify_message(channel, bytes.data(), size, key_of(9)).status, AuthStatus::other_key);
  // Every byte flipped: refused, never valid (a flip in the key id reads as another key, in a
  // length as a malformed message).
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    auto changed = bytes;
    changed[i] ^= 0x01;
    const AuthStatus s = verify_message(channel, changed.data(), size, key).status;
    ASSERT_NE(s, AuthStatus::valid) << Msg::getTypeName() << " byte " << i;
  }
  // A byte more, or one less: not a whole message.
  auto longer = bytes;
  longer.push_back(0);
  EXPECT_EQ(verify_message(channel, longer.data(), size + 1, key).status, AuthStatus::malformed);
  EXPECT_EQ(verify_message(channel, bytes.data(), size - 1, key).status, AuthStatus::malformed);
}

TEST(MessageAuth, EveryTypeSignsAndEveryChangeIsCaught) {
  every_change_is_caught(make_samples());
  every_change_is_caught(make_config());
  every_change_is_caught(make_run());
  every_change_is_caught(make_fit());
  every_change_is_caught(make_explain());
  every_change_is_caught(make_status());
}

// The tag is libsodium's crypto_auth of channel, NUL and the bytes with auth zeroed: a reader in
// another language computes the same (this pins the construction).
TEST(MessageAuth, SigningTwiceGivesTheSameTagAndTheKeyIdIsNeverZero) {
  const LabKey key = key_of(3);
  EXPECT_NE(key.id, 0);
  auto a = encoded(make_samples());
  auto b = a;
  ASSERT_TRUE(sign_encoded_message("C", a, key));
  ASSERT_TRUE(sign_encoded_message("C", b, key));
  EXPECT_EQ(a, b);
  ASSERT_TRUE(sign_encoded_message("C", a, key));  // signing a signed message again: the same
  EXPECT_EQ(a, b);
  EXPECT_NE(key_of(3).id, key_of(4).id);
}

TEST(MessageAuth, ANonMessageCannotBeSigned) {
  std::vector<unsigned char> junk(64, 0);
  std::string why;
  EXPECT_FALSE(sign_encoded_message("C", junk, key_of(1), &why));
  EXPECT_NE(why.find("not a spindown message"), std::string::npos) << why;
  EXPECT_EQ(verify_message("C", junk.data(), 64, key_of(1)).status, AuthStatus::malformed);
  EXPECT_EQ(auth_status_name(AuthStatus::bad_signature), "bad signature");
}

}  // namespace
}  // namespace spindown
