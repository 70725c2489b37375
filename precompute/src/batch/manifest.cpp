// Batch manifests, JSON or CSV (docs/batch.md): assets with their precompute options, resolved
// to mesh and soundbank paths, with every problem named by file and JSON path or CSV line.
#include <glob.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <optional>
#include <set>

#include "chladni/core/error.hpp"
#include "chladni/core/input_file.hpp"
#include "chladni/core/json_reader.hpp"
#include "chladni/precompute/batch.hpp"
#include "manifest_options.hpp"

namespace chladni::precompute::batch {

namespace fs = std::filesystem;
using json_reader::json;

namespace {

// One manifest entry before its paths are resolved: a mesh path or glob and its options.
struct Entry {
  std::string mesh, output, name, where;
  Options options;
};

bool is_glob(const std::string& s) {
  return s.find_first_of("*?[") != std::string::npos;
}

std::string resolve(const fs::path& base, const std::string& p) {
  const fs::path path(p);
  const fs::path out = (path.is_absolute() ? path : base / path).lexically_normal();
  return (out.has_filename() || out == out.root_path() ? out : out.parent_path()).string();
}

std::vector<std::string> expand_glob(const std::string& pattern, const std::string& where) {
  glob_t g{};
  const int rc = ::glob(pattern.c_str(), 0, nullptr, &g);
  std::vector<std::string> out;
  if (rc == 0)
    for (std::size_t i = 0; i < g.gl_pathc; ++i) {
      std::error_code ec;  // unreadable matches are skipped, not thrown
      if (fs::is_regular_file(g.gl_pathv[i], ec)) out.emplace_back(g.gl_pathv[i]);
    }
  ::globfree(&g);
  if (out.empty()) throw InputError(where + ": '" + pattern + "' matches no file");
  return out;
}

void check_name(const std::string& name, const std::string& where) {
  if (name.empty() || name.front() == '.' || name.find('/') != std::string::npos ||
      name.size() > 200)
    throw InputError(where + ": name '" + name +
                     "' must be a plain file name (no '/', not starting with '.')");
}

Entry json_entry(const json& e, const std::string& where, const OptionSchema& schema) {
  Entry entry;
  entry.where = where;
  if (e.is_string()) {
    entry.mesh = e.get<std::string>();
    return entry;
  }
  if (!e.is_object())
    throw InputError(where + ": expected a mesh path or an object, got " + e.type_name());
  for (auto it = e.begin(); it != e.end(); ++it) {
    const std::string& key = it.key();
    if (key == "mesh" || key == "output" || key == "name") {
      if (!it->is_string())
        throw InputError(where + "." + key + ": expected a string, got " + it->type_name());
      (key == "mesh" ? entry.mesh : key == "output" ? entry.output : entry.name) = *it;
    } else {
      set_json_option(entry.options, key, *it, where + "." + key, schema);
    }
  }
  if (entry.mesh.empty()) throw InputError(where + ": missing required field 'mesh'");
  return entry;
}

std::vector<Entry> read_json_manifest(const std::string& path, std::string& output_dir,
                                      const OptionSchema& schema) {
  const json j = json_reader::read_json_file(path, "manifest");
  const std::string root = path + ": $";
  if (!j.is_object()) throw InputError(root + ": expected an object, got " + j.type_name());
  Options defaults;
  std::vector<Entry> entries;
  bool have_assets = false;
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string at = root + "." + it.key();
    if (it.key() == "output_dir") {
      if (!it->is_string()) throw InputError(at + ": expected a string");
      output_dir = *it;
    } else if (it.key() == "defaults") {
      if (!it->is_object()) throw InputError(at + ": expected an object of precompute options");
      for (auto d = it->begin(); d != it->end(); ++d)
        set_json_option(defaults, d.key(), *d, at + "." + d.key(), schema);
    } else if (it.key() == "assets") {
      if (!it->is_array()) throw InputError(at + ": expected an array");
      have_assets = true;
      for (std::size_t i = 0; i < it->size(); ++i)
        entries.push_back(json_entry((*it)[i], at + "[" + std::to_string(i) + "]", schema));
    } else {
      throw InputError(root + ": unknown field '" + it.key() +
                       "' (expected output_dir, defaults, assets)");
    }
  }
  if (!have_assets) throw InputError(root + ": missing required field 'assets'");
  for (Entry& e : entries) e.options = merged(defaults, e.options);
  return entries;
}

std::vector<Entry> read_csv_manifest(const std::string& path, const OptionSchema& schema) {
  const std::vector<std::uint8_t> bytes = read_input_file(path, "manifest", kMaxTextInputBytes);
  const std::vector<CsvRow> rows = parse_csv(std::string(bytes.begin(), bytes.end()), path);
  if (rows.empty()) throw InputError(path + ": no header line (expected mesh,OPTION,...)");
  const CsvRow& header = rows.front();
  std::vector<std::string> columns;
  std::set<std::string> seen;
  for (const std::string& c : header.cells) {
    const std::string name = normalized_key(c);
    if (!seen.insert(name).second)
      throw InputError(path + ":" + std::to_string(header.line) + ": column '" + c +
                       "' appears twice");
    columns.push_back(name);
  }
  if (!seen.count("mesh"))
    throw InputError(path + ":" + std::to_string(header.line) + ": no 'mesh' column");
  std::vector<Entry> entries;
  for (std::size_t r = 1; r < rows.size(); ++r) {
    const std::string where = path + ":" + std::to_string(rows[r].line);
    if (rows[r].cells.size() != columns.size())
      throw InputError(where + ": " + std::to_string(rows[r].cells.size()) +
                       " fields, the header has " + std::to_string(columns.size()));
    Entry e;
    e.where = where;
    for (std::size_t c = 0; c < columns.size(); ++c) {
      const std::string& v = rows[r].cells[c];
      if (columns[c] == "mesh")
        e.mesh = v;
      else if (columns[c] == "output")
        e.output = v;
      else if (columns[c] == "name")
        e.name = v;
      else
        set_text_option(e.options, columns[c], v, where + ": column '" + columns[c] + "'", schema);
    }
    if (e.mesh.empty()) throw InputError(where + ": the mesh field is empty");
    entries.push_back(std::move(e));
  }
  return entries;
}

// Entries to assets: globs expanded, paths resolved, names and outputs unique.
std::vector<Asset> resolve_entries(const std::vector<Entry>& entries, const fs::path& base,
                                   const std::string& output_dir, const OptionSchema& schema) {
  std::vector<Asset> assets;
  std::map<std::string, std::string> names, outputs;  // -> where
  for (const Entry& e : entries) {
    const bool glob = is_glob(e.mesh);
    if (glob && (!e.output.empty() || !e.name.empty()))
      throw InputError(e.where + ": 'output' and 'name' need a single mesh, not a pattern");
    std::vector<std::string> meshes{resolve(base, e.mesh)};
    if (glob) meshes = expand_glob(meshes.front(), e.where);
    for (const std::string& mesh : meshes) {
      Asset a;
      a.mesh = mesh;
      a.where = e.where;
      a.name = e.name.empty() ? fs::path(mesh).stem().string() : e.name;
      check_name(a.name, e.where);
      a.output = e.output.empty() ? resolve(output_dir, a.name + ".chbank")
                                  : resolve(output_dir, e.output);
      a.args = to_args(e.options);
      try {
        const OptionSchema::Own own = schema.check(a.mesh, a.output, a.args);
        a.own_memory = own.memory;
        a.own_threads = own.threads;
      } catch (const InputError& err) {
        throw InputError(e.where + ": " + err.what());
      }
      std::error_code ec;
      const auto size = fs::file_size(mesh, ec);
      a.cost = ec ? 0 : size;
      if (!names.emplace(a.name, e.where).second)
        throw InputError(e.where + ": asset name '" + a.name + "' is also used by " +
                         names[a.name] + " (give one of them a \"name\" or an \"output\")");
      if (!outputs.emplace(a.output, e.where).second)
        throw InputError(e.where + ": output " + a.output + " is also written by " +
                         outputs[a.output]);
      if (a.output == a.mesh) throw InputError(e.where + ": the output would replace the mesh");
      assets.push_back(std::move(a));
    }
  }
  return assets;
}

}  // namespace

Manifest read_manifest(const std::string& path, const std::string& output_dir,
                       const OptionSchema& schema) {
  Manifest m;
  m.path = path;
  const bool csv = fs::path(path).extension() == ".csv";
  std::string dir_in_file;
  const std::vector<Entry> entries =
      csv ? read_csv_manifest(path, schema) : read_json_manifest(path, dir_in_file, schema);
  const fs::path base = fs::path(path).parent_path();
  if (!output_dir.empty())
    m.output_dir = resolve(fs::current_path(), output_dir);
  else
    m.output_dir = resolve(base, dir_in_file.empty() ? "." : dir_in_file);
  m.assets = resolve_entries(entries, base, m.output_dir, schema);
  if (m.assets.empty()) throw InputError(path + ": lists no assets");
  return m;
}

}  // namespace chladni::precompute::batch
