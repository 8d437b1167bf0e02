#pragma once
// A process's session: a random 64-bit id chosen once at its start (getrandom(2)). With the host
// name it tells one run of a program from another: a restarted bridge (a replugged board, a
// `systemctl restart`) is a new session, so its samples are a new stream and never "repeated";
// two instances of one service name are told apart (issue 31; docs/security.md).
#include <cstdint>
#include <string>
#include <string_view>

namespace spindown {

// 64 random bits, never 0 (0 means "not known": a message from a sender that names no session).
// Throws std::runtime_error when the kernel's random source fails (it does not on Linux ≥ 3.17).
std::uint64_t new_session_id();

// "3f9a0c1d5e7b2a48": the id as 16 lowercase hex digits (what messages, logs and tables print).
std::string session_text(std::uint64_t session);

// A source as messages name it: "host bench-pc-2 (session 3f9a0c1d5e7b2a48)", or "an unnamed
// source (…)" for a message from before sources were named (no host, session 0).
std::string source_text(std::string_view host, std::uint64_t session);
// A name from a received message as it can be printed: at most 64 bytes, bytes that are not
// UTF-8 escaped (\xNN), control characters as '?'.
std::string shown_name(std::string_view name);

}  // namespace spindown
