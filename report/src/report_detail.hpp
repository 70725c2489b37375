#pragma once
// The report's web files, embedded at build time (report/embed_assets.cmake).
#include <cstddef>
#include <string_view>

namespace chladni::report {

struct Asset {
  const char* name;
  std::string_view text;
};
extern const Asset kAssets[];
extern const std::size_t kAssetCount;

}  // namespace chladni::report
