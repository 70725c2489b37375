#include <cstdio>
#include <filesystem>
#include <string>

#include "chladni/core/error.hpp"
#include "chladni/core/output_file.hpp"
#include "chladni/report/report.hpp"
#include "report_detail.hpp"

namespace chladni::report {
namespace {

namespace fs = std::filesystem;

void write_file(const fs::path& path, std::string_view text) {
  const std::string p = path.string();
  const std::string tmp = temporary_path(p);
  {
    std::FILE* f = std::fopen(tmp.c_str(), "wb");
    if (!f) throw InputError(p + ": cannot open for writing");
    const bool ok = std::fwrite(text.data(), 1, text.size(), f) == text.size();
    if (std::fclose(f) != 0 || !ok) {
      std::remove(tmp.c_str());
      throw InputError(p + ": writing failed (disk full?)");
    }
  }
  commit_temporary(tmp, p, "report file");
}

}  // namespace

ReportSummary write_report(const std::string& dir, const Soundbank& bank, const ReportOptions& o) {
  const fs::path d(dir);
  std::error_code ec;
  if (fs::exists(d, ec) && !fs::is_directory(d, ec))
    throw InputError(dir + ": exists and is not a folder (the report is a folder)");
  // All the work first: a refused bank or mesh leaves the folder as it was.
  ReportSummary summary;
  const std::string data = "window.CHLADNI_REPORT = " + report_json(bank, o, &summary) + ";\n";
  summary.bytes = data.size();
  fs::create_directories(d, ec);
  if (ec) throw InputError(dir + ": cannot create the folder (" + ec.message() + ")");
  for (std::size_t i = 0; i < kAssetCount; ++i) write_file(d / kAssets[i].name, kAssets[i].text);
  write_file(d / "bank-data.js", data);
  return summary;
}

}  // namespace chladni::report
