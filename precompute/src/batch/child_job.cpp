// The batch's job file: what one child precompute runs, in keys of this library's own.
#include <nlohmann/json.hpp>

#include "chladni/core/error.hpp"
#include "chladni/core/input_file.hpp"
#include "chladni/core/output_file.hpp"
#include "chladni/precompute/batch.hpp"

namespace chladni::precompute::batch {
namespace {

using json = nlohmann::json;

template <class T>
T field(const json& j, const char* key, const std::string& where) {
  if (!j.contains(key)) throw InputError(where + ": missing field '" + key + "'");
  try {
    return j.at(key).get<T>();
  } catch (const json::exception&) {
    throw InputError(where + "." + key + ": wrong type (" + j.at(key).type_name() + ")");
  }
}

}  // namespace

void write_child_job(const std::string& path, const ChildJob& job) {
  const json j = {{"mesh", job.mesh},       {"output", job.output},
                  {"options", job.options}, {"memory_bytes", job.memory_bytes},
                  {"threads", job.threads}, {"summary", job.summary},
                  {"stamp", job.stamp}};
  try {
    write_file_atomic(path, j.dump(2) + "\n", "batch job");
  } catch (const InputError& e) {
    throw InternalError(std::string("batch: ") + e.what());
  }
}

ChildJob read_child_job(const std::string& path) {
  const std::vector<std::uint8_t> bytes = read_input_file(path, "batch job", kMaxTextInputBytes);
  json j;
  try {
    j = json::parse(bytes.begin(), bytes.end());
  } catch (const json::parse_error& e) {
    throw InputError(path + ": not JSON: " + e.what());
  }
  if (!j.is_object()) throw InputError(path + ": $: expected an object");
  const std::string w = path + ": $";
  for (const auto& [key, value] : j.items())
    if (key != "mesh" && key != "output" && key != "options" && key != "memory_bytes" &&
        key != "threads" && key != "summary" && key != "stamp")
      throw InputError(w + "." + key + ": unknown field");
  ChildJob job;
  job.mesh = field<std::string>(j, "mesh", w);
  job.output = field<std::string>(j, "output", w);
  job.options = field<std::vector<std::string>>(j, "options", w);
  job.memory_bytes = field<double>(j, "memory_bytes", w);
  job.threads = field<int>(j, "threads", w);
  job.summary = field<std::string>(j, "summary", w);
  job.stamp = field<std::string>(j, "stamp", w);
  if (job.threads < 0 || job.threads > 1024) throw InputError(w + ".threads: not in [0, 1024]");
  return job;
}

}  // namespace chladni::precompute::batch
