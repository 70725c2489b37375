#include "chladni/core/output_file.hpp"

#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "chladni/core/error.hpp"

namespace chladni {

namespace fs = std::filesystem;

void check_output_path(const std::string& path, const std::string& what) {
  if (path.empty()) throw InputError(what + ": the output path is empty");
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw InputError(what + " " + path + ": is a directory");
  const fs::path folder = fs::path(path).parent_path();
  if (!folder.empty() && !fs::is_directory(folder, ec))
    throw InputError(what + " " + path + ": folder " + folder.string() + " does not exist");
  const std::string dir = folder.empty() ? std::string(".") : folder.string();
  if (::access(dir.c_str(), W_OK) != 0)
    throw InputError(what + " " + path + ": folder " + dir + " is not writable");
}

std::string temporary_path(const std::string& path) {
  return path + ".tmp" + std::to_string(::getpid());
}

void remove_stale_temporaries(const std::string& path) {
  const fs::path out(path);
  const fs::path dir = out.parent_path().empty() ? fs::path(".") : out.parent_path();
  const std::string prefix = out.filename().string() + ".tmp";
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    if (name.size() > prefix.size() && name.rfind(prefix, 0) == 0 &&
        name.find_first_not_of("0123456789", prefix.size()) == std::string::npos)
      fs::remove(e.path(), ec);
  }
}

void commit_temporary(const std::string& tmp, const std::string& path, const std::string& what) {
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw InputError("cannot write " + what + " " + path + ": " + ec.message());
  }
}

void write_file_atomic(const std::string& path, std::string_view bytes, const std::string& what) {
  const std::string tmp = temporary_path(path);
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    if (!f) throw InputError("cannot write " + what + " " + path + ": cannot open " + tmp);
    f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!f.flush()) {
      f.close();
      std::error_code ignored;
      fs::remove(tmp, ignored);
      throw InputError("cannot write " + what + " " + path + ": write failed");
    }
  }
  commit_temporary(tmp, path, what);
}

}  // namespace chladni
