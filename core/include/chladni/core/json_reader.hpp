#pragma once
// Reading JSON inputs (scenes, paper animations) so that every problem names its JSON path,
// unknown keys are reported instead of ignored, and syntax errors carry a line and column.
#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "chladni/core/error.hpp"
#include "chladni/core/scene.hpp"

namespace chladni::json_reader {

using nlohmann::json;

[[noreturn]] inline void fail(const std::string& path, const std::string& what) {
  throw InputError(path + ": " + what);
}

// A JSON object being read, remembering its path and which keys were consumed so that typos
// ("impluse") are reported instead of silently ignored.
class Obj {
 public:
  Obj(const json& j, std::string path) : j_(j), path_(std::move(path)) {
    if (!j_.is_object()) fail(path_, std::string("expected an object, got ") + j_.type_name());
  }
  const std::string& path() const { return path_; }
  std::string at(const std::string& key) const { return path_ + "." + key; }
  bool has(const std::string& key) const { return j_.contains(key); }

  const json& get(const std::string& key) {
    if (!j_.contains(key)) fail(path_, "missing required field '" + key + "'");
    used_.push_back(key);
    return j_.at(key);
  }
  double number(const std::string& key) {
    const json& v = get(key);
    if (!v.is_number()) fail(at(key), std::string("expected a number, got ") + v.type_name());
    const double x = v.get<double>();
    if (!std::isfinite(x)) fail(at(key), "must be finite");
    return x;
  }
  double number(const std::string& key, double fallback) {
    return has(key) ? number(key) : fallback;
  }
  double positive(const std::string& key, double fallback) {
    const double x = number(key, fallback);
    if (!(x > 0)) fail(at(key), "must be > 0");
    return x;
  }
  double non_negative(const std::string& key, double fallback) {
    const double x = number(key, fallback);
    if (x < 0) fail(at(key), "must be >= 0");
    return x;
  }
  long integer(const std::string& key) {
    const json& v = get(key);
    if (!v.is_number_integer()) fail(at(key), "expected an integer");
    return v.get<long>();
  }
  std::string string(const std::string& key) {
    const json& v = get(key);
    if (!v.is_string()) fail(at(key), std::string("expected a string, got ") + v.type_name());
    return v.get<std::string>();
  }
  Vec3 vec3(const std::string& key) {
    const json& v = get(key);
    if (!v.is_array() || v.size() != 3) fail(at(key), "expected an array of 3 numbers");
    Vec3 out{};
    for (int k = 0; k < 3; ++k) {
      if (!v[k].is_number()) fail(at(key) + "[" + std::to_string(k) + "]", "expected a number");
      out[k] = v[k].get<double>();
      if (!std::isfinite(out[k])) fail(at(key) + "[" + std::to_string(k) + "]", "must be finite");
    }
    return out;
  }
  Vec3 unit(const std::string& key) {
    Vec3 v = vec3(key);
    const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (!(n > 1e-12)) fail(at(key), "must be a non-zero vector");
    return {v[0] / n, v[1] / n, v[2] / n};
  }
  Quat quaternion(const std::string& key) {
    const json& v = get(key);
    if (!v.is_array() || v.size() != 4) fail(at(key), "expected a quaternion [w, x, y, z]");
    Quat q{};
    double n = 0;
    for (int k = 0; k < 4; ++k) {
      if (!v[k].is_number()) fail(at(key) + "[" + std::to_string(k) + "]", "expected a number");
      q[k] = v[k].get<double>();
      if (!std::isfinite(q[k])) fail(at(key) + "[" + std::to_string(k) + "]", "must be finite");
      n += q[k] * q[k];
    }
    if (!(n > 1e-12)) fail(at(key), "must be a non-zero quaternion");
    for (double& c : q) c /= std::sqrt(n);
    return q;
  }
  const json& array(const std::string& key) {
    const json& v = get(key);
    if (!v.is_array()) fail(at(key), std::string("expected an array, got ") + v.type_name());
    return v;
  }
  // Every key must have been read: anything else is a typo or an unsupported field.
  void done() const {
    for (auto it = j_.begin(); it != j_.end(); ++it) {
      if (std::find(used_.begin(), used_.end(), it.key()) == used_.end()) {
        fail(path_, "unknown field '" + it.key() + "'");
      }
    }
  }

 private:
  const json& j_;
  std::string path_;
  std::vector<std::string> used_;
};

inline std::string index_path(const std::string& base, std::size_t i) {
  return base + "[" + std::to_string(i) + "]";
}

/// Parses JSON text read from `path`: a syntax error or an overflowing number names
/// file:line:column, a duplicate key names its JSON path (nlohmann would keep the last).
json parse_json_text(std::string_view text, const std::string& path);

/// Reads (read_input_file, at most kMaxTextInputBytes) and parses a JSON file. `what` names the
/// kind of file.
json read_json_file(const std::string& path, const char* what);

}  // namespace chladni::json_reader
