// One capture judged as `validate` judges it, for validate and diff alike: the layout, the rules,
// the clock and the time window of the command line, and the report the capture gives.
#pragma once

#include <cstdio>
#include <string>
#include <vector>

#include "commands.hpp"
#include "ncservo/base/error.hpp"
#include "ncservo/capture/capture_stream.hpp"
#include "ncservo/layout/eni.hpp"
#include "ncservo/report/report.hpp"

namespace ncservo::cli {

// What judges a capture, for validate and diff alike: the layout, the rules, the clock, the window.
struct CheckArgs : RuleArgs {
  LayoutArgs layout;
  std::string timestamps = "auto";
  WindowArgs window;
  std::string read_thread = kReadThreadDefault;
};

// CheckArgs made ready: the files loaded, the settings built, the window checked.
struct CheckSetup {
  LayoutFiles files;
  RuleSettings settings;
  TimeWindow window;
  TimestampMode timestamps = TimestampMode::Auto;
  DecoderOptions layout;
  // The ENI's tasks, whose cycle times the capture is held against
  // (docs/layout.md#eni-cycle-times).
  std::vector<EniCyclicFrame> eni_frames;
};

// A usage error (exit 2) when a file or an option is wrong.
Result<CheckSetup> prepareCheck(const CheckArgs& o);

// Where one capture's report goes while it is made: to the writer as it comes (one capture at
// a time), or, with `live` null, kept whole with its messages for the writer (captures in
// parallel, written in argument order by presentCapture).
struct CaptureOutput {
  report::ReportWriter* live;
  std::FILE* messages;  // standard error, or the capture's own buffer
};

// Runs one capture through the validator. Returns the capture's exit status (0, 1, 3 or 4), or
// 130 when Ctrl-C stopped it (its report unfinished, `frames` the frames read).
int validateCapture(const std::string& path, const CheckSetup& setup,
                    const report::ReportWriter& writer, const CaptureOutput& output,
                    report::CaptureReport& report, CaptureThreads threads);

}  // namespace ncservo::cli
