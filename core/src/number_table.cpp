#include "chladni/core/number_table.hpp"

#include <charconv>
#include <cmath>
#include <string_view>

#include "chladni/core/error.hpp"
#include "chladni/core/input_file.hpp"

namespace chladni {

std::vector<std::vector<double>> read_number_rows(const std::string& path, std::size_t min_cols,
                                                  std::size_t max_cols, const std::string& what) {
  const std::vector<uint8_t> bytes = read_input_file(path, what, kMaxTextInputBytes);
  const std::string_view text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  std::vector<std::vector<double>> rows;
  std::size_t start = 0;
  for (std::size_t n = 1; start < text.size(); ++n) {
    std::size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(start, end - start);
    start = end + 1;
    line = line.substr(0, line.find('#'));
    const std::string where = path + ":" + std::to_string(n);
    std::vector<double> row;
    for (std::size_t a = line.find_first_not_of(" \t\r"); a != std::string_view::npos;
         a = line.find_first_not_of(" \t\r", a)) {
      const std::size_t b = std::min(line.find_first_of(" \t\r", a), line.size());
      std::string_view tok = line.substr(a, b - a);
      a = b;
      if (tok.size() > 1 && tok[0] == '+') tok.remove_prefix(1);
      double v = 0;
      const auto [p, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), v);
      if (ec != std::errc() || p != tok.data() + tok.size() || !std::isfinite(v))
        throw InputError(where + ": '" + std::string(tok) + "' is not a finite number");
      row.push_back(v);
      if (row.size() > max_cols) break;
    }
    if (row.empty()) continue;
    if (row.size() < min_cols || row.size() > max_cols)
      throw InputError(
          where + ": expected " +
          (min_cols == max_cols ? std::to_string(min_cols)
                                : std::to_string(min_cols) + " to " + std::to_string(max_cols)) +
          " numbers, found " + (row.size() > max_cols ? "more" : std::to_string(row.size())));
    rows.push_back(std::move(row));
  }
  return rows;
}

}  // namespace chladni
