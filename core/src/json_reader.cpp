#include "chladni/core/json_reader.hpp"

#include <fstream>
#include <sstream>

namespace chladni::json_reader {

json read_json_file(const std::string& path, const char* what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError("cannot open " + std::string(what) + " file " + path);
  std::stringstream buf;
  buf << in.rdbuf();
  const std::string text = buf.str();
  try {
    return json::parse(text);
  } catch (const json::parse_error& e) {
    // Turn the byte offset into a line and column a person can find.
    std::size_t line = 1, col = 1;
    for (std::size_t k = 0; k + 1 < e.byte && k < text.size(); ++k) {
      if (text[k] == '\n')
        ++line, col = 1;
      else
        ++col;
    }
    throw InputError(path + ":" + std::to_string(line) + ":" + std::to_string(col) +
                     ": JSON syntax error: " + e.what());
  }
}

}  // namespace chladni::json_reader
