#include "chladni/tools/paper_db_cache.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <cerrno>

#include <array>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>

#include "chladni/core/error.hpp"
#include "chladni/core/output_file.hpp"
#include "chladni/tools/paper_db_generate.hpp"

namespace chladni::tools {
namespace {

constexpr char kMagic[8] = {'C', 'H', 'P', 'D', 'B', 'S', 'N', 'P'};
// Bump when generate_paper_database's output changes: old snapshots are then not read.
constexpr uint32_t kGeneration = 2;
constexpr std::uintmax_t kMaxSnapshotBytes = 1ull << 30;

class Writer {
 public:
  template <class T>
  void put(T v) {
    bytes.append(reinterpret_cast<const char*>(&v), sizeof v);
  }
  void floats(const std::vector<float>& v) {  // padded to 8 bytes
    put<uint64_t>(v.size());
    bytes.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(float));
    if (v.size() % 2) put<float>(0.0f);
  }
  void text(const std::string& s) {  // padded to 8 bytes: the floats after it stay aligned
    put<uint64_t>(s.size());
    bytes += s;
    bytes.append((8 - s.size() % 8) % 8, '\0');
  }
  std::string bytes;
};

class Reader {
 public:
  Reader(std::string_view bytes, std::string file) : b_(bytes), file_(std::move(file)) {}
  template <class T>
  T get() {
    T v;
    need(sizeof v);
    std::memcpy(&v, b_.data() + at_, sizeof v);
    at_ += sizeof v;
    return v;
  }
  uint64_t count(uint64_t item_bytes) {
    const uint64_t n = get<uint64_t>();
    if (n > (b_.size() - at_) / item_bytes)
      fail("a count of " + std::to_string(n) + " overruns it");
    return n;
  }
  std::vector<float> floats() {
    const uint64_t n = count(sizeof(float));
    // Aligned (the writer pads every field to 8 bytes and the file is mapped at a page).
    const auto* p = reinterpret_cast<const float*>(b_.data() + at_);
    std::vector<float> v(p, p + n);
    skip((n + n % 2) * sizeof(float));
    return v;
  }
  std::string text() {
    const uint64_t n = count(1);
    std::string s(b_.substr(at_, n));
    skip(n + (8 - n % 8) % 8);
    return s;
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(file_ + ": paper database snapshot at byte " + std::to_string(at_) + ": " +
                     what);
  }
  bool done() const { return at_ == b_.size(); }

 private:
  void need(std::size_t n) const {
    if (b_.size() - at_ < n) fail("truncated");
  }
  void skip(std::size_t n) {
    need(n);
    at_ += n;
  }
  std::string_view b_;
  std::string file_;
  std::size_t at_ = 0;
};

// A read-only mapping of a whole file (no copy: the snapshot is read in place).
class Mapping {
 public:
  explicit Mapping(const std::string& file) {
    const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) throw InputError(file + ": cannot open it: " + std::strerror(errno));
    struct stat st {};
    if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode) ||
        static_cast<std::uintmax_t>(st.st_size) > kMaxSnapshotBytes) {
      ::close(fd);
      throw InputError(file + ": not a readable snapshot");
    }
    size_ = static_cast<std::size_t>(st.st_size);
    if (size_ > 0) {
      void* p = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE | MAP_POPULATE, fd, 0);
      if (p == MAP_FAILED) {
        ::close(fd);
        throw InputError(file + ": cannot map it: " + std::strerror(errno));
      }
      data_ = static_cast<const char*>(p);
    }
    ::close(fd);
  }
  ~Mapping() {
    if (data_) ::munmap(const_cast<char*>(data_), size_);
  }
  Mapping(const Mapping&) = delete;
  Mapping& operator=(const Mapping&) = delete;
  std::string_view bytes() const { return {data_ ? data_ : "", size_}; }

 private:
  const char* data_ = nullptr;
  std::size_t size_ = 0;
};

uint32_t crc(std::string_view bytes) {
  return static_cast<uint32_t>(
      crc32(0L, reinterpret_cast<const Bytef*>(bytes.data()), static_cast<uInt>(bytes.size())));
}

}  // namespace

std::filesystem::path cache_dir() {
  if (const char* d = std::getenv("CHLADNI_CACHE_DIR")) return d;
  if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x)
    return std::filesystem::path(x) / "chladni";
  if (const char* h = std::getenv("HOME"); h && *h)
    return std::filesystem::path(h) / ".cache" / "chladni";
  return {};
}

std::filesystem::path paper_db_snapshot_path(const std::filesystem::path& dir) {
  return dir / ("paper-db-default-g" + std::to_string(kGeneration) + ".bin");
}

void write_paper_db_snapshot(const std::filesystem::path& path, const runtime::PaperSoundDb& db) {
  Writer w;
  w.bytes.append(kMagic, sizeof kMagic);
  w.put<uint32_t>(kGeneration);
  w.put<uint32_t>(0);  // padding
  w.put<double>(db.sample_rate);
  w.put<double>(db.friction_reference_speed);
  w.text(db.description);
  w.put<uint64_t>(db.entries.size());
  for (const runtime::PaperDbEntry& e : db.entries) {
    w.put<uint64_t>(e.constrained);
    w.put<double>(e.l_r);
    w.put<double>(e.l_c);
    w.put<uint64_t>(e.crumple.size());
    for (const auto& clip : e.crumple) w.floats(clip);
    w.put<uint64_t>(e.friction.size());
    for (const auto& [surface, spectra] : e.friction) {
      w.text(surface);
      w.put<uint64_t>(spectra.size());
      for (const auto& s : spectra) w.floats(s);
    }
  }
  w.put<uint32_t>(crc(w.bytes));
  write_file_atomic(path.string(), w.bytes, "paper database snapshot");
}

runtime::PaperSoundDb read_paper_db_snapshot(const std::filesystem::path& path) {
  const std::string file = path.string();
  const Mapping map(file);
  std::string_view bytes = map.bytes();
  const std::size_t size = bytes.size();
  if (size < sizeof kMagic + 8 || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
    throw InputError(file + ": not a paper database snapshot");
  uint32_t stored;
  std::memcpy(&stored, bytes.data() + size - 4, 4);
  bytes = bytes.substr(0, size - 4);
  if (crc(bytes) != stored) throw InputError(file + ": CRC mismatch (damaged or partly written)");
  Reader r(bytes, file);
  r.get<std::array<char, 8>>();
  if (r.get<uint32_t>() != kGeneration) r.fail("written by another generator version");
  r.get<uint32_t>();  // padding
  runtime::PaperSoundDb db;
  db.sample_rate = r.get<double>();
  db.friction_reference_speed = r.get<double>();
  db.description = r.text();
  db.entries.resize(r.count(8 * 3));
  for (runtime::PaperDbEntry& e : db.entries) {
    e.constrained = r.get<uint64_t>() != 0;
    e.l_r = r.get<double>();
    e.l_c = r.get<double>();
    e.crumple.resize(r.count(8));
    for (auto& clip : e.crumple) clip = r.floats();
    for (uint64_t n = r.count(16); n > 0; --n) {
      std::string surface = r.text();
      auto& spectra = e.friction[surface];
      spectra.resize(r.count(8));
      for (auto& s : spectra) s = r.floats();
    }
  }
  if (!r.done()) r.fail("trailing bytes");
  try {
    db.validate();
  } catch (const InputError& e) {
    throw InputError(file + ": " + e.what());
  }
  return db;
}

runtime::PaperSoundDb default_paper_database(const std::filesystem::path& dir, std::string& note) {
  const auto t0 = std::chrono::steady_clock::now();
  auto seconds = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };
  const std::filesystem::path snap = dir.empty() ? dir : paper_db_snapshot_path(dir);
  std::string why;
  if (!snap.empty() && std::filesystem::exists(snap)) {
    try {
      runtime::PaperSoundDb db = read_paper_db_snapshot(snap);
      char line[64];
      std::snprintf(line, sizeof line, " (%.2f s)", seconds());
      note = "read the default paper sound database from " + snap.string() + line;
      return db;
    } catch (const InputError& e) {
      why = std::string("; the cached copy was unusable (") + e.what() + ")";
    }
  }
  runtime::PaperSoundDb db = tools::generate_paper_database({});
  char took[64];
  std::snprintf(took, sizeof took, "%.1f s", seconds());
  note = std::string("generated the default paper sound database (") + took + why + ")";
  if (snap.empty()) return db;
  try {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    write_paper_db_snapshot(snap, db);
    note += "; cached in " + snap.string();
    for (const auto& f : std::filesystem::directory_iterator(dir, ec)) {  // older generations
      const std::string name = f.path().filename().string();
      if (name.starts_with("paper-db-default-g") && f.path() != snap)
        std::filesystem::remove(f.path(), ec);
    }
  } catch (const InputError& e) {  // a cache that cannot be written costs time, not the run
    note += std::string("; not cached: ") + e.what();
  }
  return db;
}

}  // namespace chladni::tools
