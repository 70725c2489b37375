#pragma once
// Plain-text tables of numbers (radiate's velocity and point files): whitespace-separated finite
// numbers, one row per line, '#' comments and blank lines skipped.
#include <cstddef>
#include <string>
#include <vector>

namespace chladni {

/// The rows of `path` (at most kMaxTextInputBytes), each with min_cols..max_cols numbers.
/// Throws InputError naming `what`, the file and the line of the first bad row or number.
std::vector<std::vector<double>> read_number_rows(const std::string& path, std::size_t min_cols,
                                                  std::size_t max_cols, const std::string& what);

}  // namespace chladni
