#include "spindown/message_stamp.hpp"

#include "spindown/clock.hpp"
#include "spindown/host_name.hpp"
#include "spindown/lcm_url.hpp"
#include "spindown/message_auth.hpp"
#include "spindown/session_id.hpp"

namespace spindown {

SourceIdentity this_process_identity(std::string lab, const std::string& lcm_url) {
  SourceIdentity id;
  id.lab = std::move(lab);
  id.sent_to = lcm_destination(lcm_url);
  id.host = host_name();
  id.session = new_session_id();
  id.start_utime = wall_us();
  return id;
}

bool MessageStamp::sign(std::string_view channel, std::vector<unsigned char>& bytes) const {
  return sign_encoded_message(channel, bytes, *key_);
}

}  // namespace spindown
