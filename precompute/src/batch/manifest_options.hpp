#pragma once
// Precompute options as a manifest states them: named like the command's long options (with or
// without dashes, '_' for '-'), merged over the manifest's defaults, turned into arguments.
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "chladni/precompute/batch.hpp"

namespace chladni::precompute::batch {

struct OptionValue {
  bool set = false;   ///< false: explicitly unset (JSON null, a false flag)
  bool flag = false;  ///< a flag: no value follows it
  std::string text;
};
/// By normalized long name, so the arguments come out in one canonical order.
using Options = std::map<std::string, OptionValue>;

/// "--max_modes" and "max_modes" become "max-modes".
std::string normalized_key(const std::string& key);

/// Sets `key` from a JSON value (string, number, boolean for a flag, null to unset). Throws
/// InputError naming `where` for an unknown or batch-managed option or a wrong type.
void set_json_option(Options& options, const std::string& key, const nlohmann::json& value,
                     const std::string& where, const OptionSchema& schema);
/// Sets `key` from a CSV cell: empty leaves the default; a flag takes true/false/yes/no/1/0.
void set_text_option(Options& options, const std::string& key, const std::string& value,
                     const std::string& where, const OptionSchema& schema);

/// `defaults` overridden by `options`.
Options merged(const Options& defaults, const Options& options);
/// The arguments, e.g. {"--material", "brass", "--repair"}.
std::vector<std::string> to_args(const Options& options);

struct CsvRow {
  std::size_t line = 0;  ///< 1-based line where the row starts
  std::vector<std::string> cells;
};
/// RFC 4180 fields (double quotes, "" inside them), cells trimmed of spaces; blank lines and
/// lines starting with '#' are skipped. Throws InputError naming `path` and the line.
std::vector<CsvRow> parse_csv(const std::string& text, const std::string& path);

}  // namespace chladni::precompute::batch
