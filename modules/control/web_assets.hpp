// The files of the live web page (web/: TypeScript bundled by esbuild at build time), compiled
// into the binary: cmake/EmbedWebAssets.cmake turns web/dist into a generated source, so
// rackcat serves the page with nothing installed beside it and nothing fetched at run time.
#pragma once

#include <span>
#include <string_view>

namespace rackcat::modules {

struct WebAsset {
  std::string_view path;          // the request path ("/" for index.html)
  std::string_view content_type;  // with charset for text
  std::string_view body;
};

// Every embedded file, in no particular order.
std::span<const WebAsset> web_assets();

// The asset served at `path`, or null.
const WebAsset* find_web_asset(std::string_view path);

}  // namespace rackcat::modules
