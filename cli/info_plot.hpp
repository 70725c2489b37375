#pragma once
// chladni info BANK --plot OUT.png: the modes' damping ratios against frequency with the
// material's damping curve, and each mode's radiation at 1 m by the gain rule the runtime uses.
#include <string>

#include "chladni/core/soundbank.hpp"

namespace chladni::cli {

/// InputError naming `path` when it cannot be written.
void write_info_plot(const std::string& path, const std::string& bank_path, const Soundbank& bank);

}  // namespace chladni::cli
