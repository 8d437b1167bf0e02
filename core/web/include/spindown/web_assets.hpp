#pragma once
// The pages' files, built into the program (a lab network has no internet, and the service
// must not depend on files beside it): the room and bench pages, their scripts and style, the
// icon, and uPlot (third_party/uplot/, MIT) with its licence. Made at build time from
// core/web/assets/ and third_party/uplot/ by cmake/embed_assets.cmake.
#include <span>
#include <string_view>

namespace spindown {

struct WebAsset {
  std::string_view path;          // "/assets/room.js", "/assets/uplot/uPlot.iife.min.js", …
  std::string_view content_type;  // "text/javascript; charset=utf-8", …
  std::string_view data;
};

std::span<const WebAsset> web_assets();
const WebAsset* find_web_asset(std::string_view path);  // null when there is none

}  // namespace spindown
