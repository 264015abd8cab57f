// `ncservo merge REPORT.json…` (docs/field.md#a-fleets-recordings): one report over many
// captures' JSON reports.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "ncservo/report/report_merge.hpp"

namespace ncservo::cli {

using namespace report;  // the report layer's names
namespace {

// The formats of the merged report: one row each.
struct MergeFormat {
  const char* name;
  std::string (*write)(const MergedReport& merged);
};
constexpr MergeFormat kMergeFormats[] = {{"json", mergedJson}, {"text", mergedText}};

struct MergeArgs {
  std::vector<std::string> reports;
  std::string format = "json";
  std::string output;
};

int runMerge(const MergeArgs& args) {
  if (Status refused = refuseInputAsOutput("-o", args.output, args.reports); !refused) {
    fmt::print(stderr, "ncservo merge: {}\n", refused.error().text());
    return kExitUsage;
  }
  MergedReport merged;
  for (const std::string& path : args.reports) {
    if (Status added = mergeReportFile(path, merged); !added) {
      fmt::print(stderr, "ncservo merge: {}\n", added.error().text());
      return kExitCapture;
    }
  }
  Result<std::FILE*> out = openOutput(args.output, args.reports);
  if (!out) {
    fmt::print(stderr, "ncservo merge: {}\n", out.error().text());
    return kExitUsage;
  }
  const std::string text = rowNamed(kMergeFormats, args.format).write(merged);
  std::fputs(text.c_str(), *out);
  if (*out != stdout && std::fclose(*out) != 0) {
    fmt::print(stderr, "ncservo merge: {}: cannot write\n", args.output);
    return kExitUsage;
  }
  return kExitOk;
}

}  // namespace

Handler mergeCommand(CLI::App& command) {
  auto args = std::make_shared<MergeArgs>();
  command.add_option("reports", args->reports, "JSON reports of validate (--format json)")
      ->required();
  addFormatOption(command, args->format, namesOf(kMergeFormats), " (default json)");
  command.add_option("-o,--output", args->output, "write the merged report to FILE");
  return [args] { return runMerge(*args); };
}

}  // namespace ncservo::cli
