#include "chladni/core/json_reader.hpp"

#include <set>

#include "chladni/core/input_file.hpp"

namespace chladni::json_reader {

namespace {

// "file:line:column" of byte offset `byte` (1-based, as nlohmann reports it).
std::string where(const std::string& path, std::string_view text, std::size_t byte) {
  std::size_t line = 1, col = 1;
  for (std::size_t k = 0; k + 1 < byte && k < text.size(); ++k) {
    if (text[k] == '\n')
      ++line, col = 1;
    else
      ++col;
  }
  return path + ":" + std::to_string(line) + ":" + std::to_string(col);
}

// Follows the parse to know the JSON path of each key, so a duplicate key (which nlohmann
// would silently resolve to the last one) is an error naming where it is.
class DuplicateKeyCheck {
 public:
  explicit DuplicateKeyCheck(std::string file) : file_(std::move(file)) {}
  bool operator()(int, json::parse_event_t event, json& parsed) {
    using E = json::parse_event_t;
    switch (event) {
      case E::object_start:
      case E::array_start:
        frames_.push_back({event == E::array_start, 0, {}, {}});
        break;
      case E::key: {
        Frame& top = frames_.back();
        top.key = parsed.get<std::string>();
        if (!top.keys.insert(top.key).second)
          throw InputError(file_ + ": " + path(frames_.size() - 1) + ": duplicate key '" + top.key +
                           "'");
        break;
      }
      case E::object_end:
      case E::array_end:
        frames_.pop_back();
        [[fallthrough]];
      case E::value:
        if (!frames_.empty() && frames_.back().is_array) ++frames_.back().index;
        break;
    }
    return true;
  }

 private:
  struct Frame {
    bool is_array;
    std::size_t index;
    std::string key;
    std::set<std::string> keys;
  };
  // JSON path ("$.objects[2].bar") of the value frame `depth` belongs to.
  std::string path(std::size_t depth) const {
    std::string p = "$";
    for (std::size_t d = 0; d < depth; ++d) {
      if (frames_[d].is_array) {
        p.append("[").append(std::to_string(frames_[d].index)).append("]");
      } else {
        p.append(".").append(frames_[d].key);
      }
    }
    return p;
  }
  std::string file_;
  std::vector<Frame> frames_;
};

}  // namespace

json parse_json_text(std::string_view text, const std::string& path) {
  try {
    return json::parse(text, DuplicateKeyCheck(path));
  } catch (const json::parse_error& e) {
    throw InputError(where(path, text, e.byte) + ": JSON syntax error: " + e.what());
  } catch (const json::out_of_range& e) {
    // nlohmann reports overflow (406) without a position: find the number in the text.
    std::string msg = e.what();
    const auto q = msg.find('\'');
    const auto q2 = q == std::string::npos ? q : msg.find('\'', q + 1);
    std::string at = path;
    if (q2 != std::string::npos) {
      const std::string literal = msg.substr(q + 1, q2 - q - 1);
      const auto pos = text.find(literal);
      if (pos != std::string::npos) at = where(path, text, pos + 1);
      msg = "the number " + literal + " does not fit a double";
    }
    throw InputError(at + ": " + msg);
  } catch (const json::exception& e) {
    throw InputError(path + ": JSON error: " + e.what());
  }
}

json read_json_file(const std::string& path, const char* what) {
  const std::vector<std::uint8_t> bytes = read_input_file(path, what, kMaxTextInputBytes);
  return parse_json_text(
      std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()), path);
}

}  // namespace chladni::json_reader
