#include <filesystem>
#include <string>

#include "chladni/core/error.hpp"
#include "chladni/core/output_file.hpp"
#include "chladni/report/report.hpp"
#include "report_detail.hpp"

namespace chladni::report {

namespace fs = std::filesystem;

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
  for (std::size_t i = 0; i < kAssetCount; ++i)
    write_file_atomic((d / kAssets[i].name).string(), kAssets[i].text, "report file");
  write_file_atomic((d / "bank-data.js").string(), data, "report data");
  return summary;
}

}  // namespace chladni::report
