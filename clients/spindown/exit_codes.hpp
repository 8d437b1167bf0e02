#pragma once
// The CLI's exit codes (design §5); scripts rely on them.
namespace spindown::cli {
inline constexpr int exit_ok = 0;
inline constexpr int exit_unusable = 1;   // a file or run could not be used; the others were processed
inline constexpr int exit_bad_usage = 2;  // bad options; nothing was processed
}  // namespace spindown::cli
