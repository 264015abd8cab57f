// libFuzzer target: a whole capture file through the CLI's reading path — libpcap through
// CaptureReader, the walker, the validator and a report in one of the five formats — as
// `ncservo validate` runs it. Input: the file's bytes.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "fuzz_common.hpp"
#include "ncservo/capture/capture_reader.hpp"
#include "ncservo/report/report.hpp"
#include "verdict.hpp"

namespace {

// The input goes to a file because CaptureReader opens paths, as the CLI does.
const std::string& inputPath() {
  static const std::string path = [] {
    const char* dir = std::getenv("TMPDIR");
    return std::string(dir != nullptr ? dir : "/tmp") + "/ncservo-fuzz-capture-" +
           std::to_string(getpid()) + ".pcap";
  }();
  return path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace ncservo;
  const std::string& path = inputPath();
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) std::abort();
  if (size > 0 && std::fwrite(data, 1, size, file) != size) std::abort();
  std::fclose(file);

  static const std::vector<std::string> formats = report::reportFormatNames();
  const report::ReportFormat* format = report::findReportFormat(formats[size % formats.size()]);
  report::ReportOptions options;
  options.enabled = RuleSettings{}.enabled;
  static const cli::PolicyJudge judge{cli::VerdictPolicy{}};
  // A device is written as it is, never renamed over.
  auto opened_writer = report::ReportWriter::open({{format, "/dev/null"}}, options, judge);
  if (!opened_writer) std::abort();
  report::ReportWriter& writer = **opened_writer;
  std::vector<report::CaptureReport> reports(1);
  report::CaptureReport& report = reports.back();
  report.path = path;
  writer.beginCapture(report);
  auto opened = CaptureReader::open(path);
  if (!opened) {
    report.error = opened.error().text();
    if (report.error->find(path) == std::string::npos) std::abort();  // messages name the file
  } else {
    CaptureReader* reader = opened->get();
    Validator validator(DecoderOptions{}, RuleSettings{});
    static EcatFrame frame;
    CaptureRecord record;
    Result<bool> status;
    while ((status = reader->next(record)) && *status) {
      if (record.frame == 1) report.first_time_ns = record.time_ns;
      report.frames = record.frame;
      fuzz::feedFrame(validator, record.link, record.frame, record.time_ns, record.data,
                      record.captured, frame);
      for (const Finding& f : validator.findings()) {
        const report::BaselineState state = report.tally(f);
        if (writer.keepsFindings()) report.findings.push_back(f);
        writer.finding(report, f, state);
      }
    }
    takeValidator(validator, report);
    if (!status) {
      report.error = status.error().text();
      if (report.error->find(path) == std::string::npos) std::abort();
    }
  }
  writer.endCapture(report);
  if (!writer.finish(reports)) std::abort();
  return 0;
}
