#pragma once
// CRC-32 as zlib's crc32() and MCAP compute it (IEEE 802.3: reflected polynomial 0xEDB88320,
// initial value and final XOR 0xFFFFFFFF), incrementally: crc32_update(crc32_update(0, a), b)
// is the CRC of a followed by b, and the CRC of nothing is 0.
#include <cstddef>
#include <cstdint>
#include <string_view>

namespace spindown {

std::uint32_t crc32_update(std::uint32_t crc, const void* data, std::size_t size);
inline std::uint32_t crc32(std::string_view bytes) { return crc32_update(0, bytes.data(), bytes.size()); }

}  // namespace spindown
