#include "manifest_options.hpp"

#include "chladni/core/error.hpp"

namespace chladni::precompute::batch {

namespace {

OptionSchema::Kind known_kind(const std::string& key, const std::string& where,
                              const OptionSchema& schema) {
  const OptionSchema::Kind kind = schema.kind(key);
  if (kind == OptionSchema::Managed)
    throw InputError(where + ": --" + key + " is set by the batch for every asset");
  if (kind == OptionSchema::Unknown)
    throw InputError(where + ": unknown precompute option '" + key +
                     "' (chladni precompute --help lists them)");
  return kind;
}

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return {};
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

}  // namespace

std::string normalized_key(const std::string& key) {
  std::string k = key.substr(std::min(key.find_first_not_of('-'), key.size()));
  for (char& c : k)
    if (c == '_') c = '-';
  return k;
}

void set_json_option(Options& options, const std::string& raw, const nlohmann::json& v,
                     const std::string& where, const OptionSchema& schema) {
  const std::string key = normalized_key(raw);
  const OptionSchema::Kind kind = known_kind(key, where, schema);
  OptionValue o;
  o.flag = kind == OptionSchema::Flag;
  if (v.is_null()) {
    options[key] = o;
    return;
  }
  if (o.flag) {
    if (!v.is_boolean()) throw InputError(where + ": a flag: expected true or false");
    o.set = v.get<bool>();
  } else if (v.is_string()) {
    o.set = true;
    o.text = v.get<std::string>();
  } else if (v.is_number()) {
    o.set = true;
    o.text = v.dump();  // the shortest text that reads back as the same number
  } else {
    throw InputError(where + ": expected a number or a string, got " + v.type_name());
  }
  options[key] = o;
}

void set_text_option(Options& options, const std::string& key, const std::string& value,
                     const std::string& where, const OptionSchema& schema) {
  const OptionSchema::Kind kind = known_kind(key, where, schema);
  if (value.empty()) return;
  OptionValue o;
  o.flag = kind == OptionSchema::Flag;
  if (o.flag) {
    if (value == "true" || value == "yes" || value == "1")
      o.set = true;
    else if (value != "false" && value != "no" && value != "0")
      throw InputError(where + ": a flag: expected true or false, not '" + value + "'");
  } else {
    o.set = true;
    o.text = value;
  }
  options[key] = o;
}

Options merged(const Options& defaults, const Options& options) {
  Options out = defaults;
  for (const auto& [k, v] : options) out[k] = v;
  return out;
}

std::vector<std::string> to_args(const Options& options) {
  std::vector<std::string> args;
  for (const auto& [k, v] : options) {
    if (!v.set) continue;
    args.push_back("--" + k);
    if (!v.flag) args.push_back(v.text);
  }
  return args;
}

std::vector<CsvRow> parse_csv(const std::string& text, const std::string& path) {
  std::vector<CsvRow> rows;
  std::size_t line = 1, i = 0;
  // Spreadsheets save "CSV UTF-8" with a byte-order mark and CRLF line ends.
  if (text.starts_with("\xEF\xBB\xBF")) i = 3;
  while (i < text.size()) {
    CsvRow row;
    row.line = line;
    std::string cell;
    bool quoted = false, was_quoted = false, end = false;
    for (; i < text.size() && !end; ++i) {
      const char c = text[i];
      if (quoted) {
        if (c == '"' && i + 1 < text.size() && text[i + 1] == '"') {
          cell += '"';
          ++i;
        } else if (c == '"') {
          quoted = false;
        } else {
          if (c == '\n') ++line;
          cell += c;
        }
      } else if (c == '"' && trim(cell).empty()) {
        quoted = was_quoted = true;
        cell.clear();
      } else if (c == ',' || c == '\n') {
        row.cells.push_back(was_quoted ? cell : trim(cell));
        cell.clear();
        was_quoted = false;
        if (c == '\n') ++line, end = true;
      } else if (was_quoted) {  // after the closing quote only blanks (a CRLF's '\r') may follow
        if (c != ' ' && c != '\t' && c != '\r')
          throw InputError(
              path + ":" + std::to_string(line) + ": '" + std::string(1, c) +
              "' after a closing quote (a quote inside a quoted field is written \"\")");
      } else {
        cell += c;
      }
    }
    if (quoted) throw InputError(path + ":" + std::to_string(row.line) + ": unterminated quote");
    if (!end) row.cells.push_back(was_quoted ? cell : trim(cell));
    const bool blank = row.cells.size() == 1 && row.cells[0].empty();
    const bool comment = !row.cells.empty() && !row.cells[0].empty() && row.cells[0][0] == '#';
    if (!blank && !comment) rows.push_back(std::move(row));
  }
  return rows;
}

}  // namespace chladni::precompute::batch
