// Test helper: runs a script's frames through a Validator and the HTML report's TimelineRecorder
// as `validate` feeds them (every copy of every cycle, numbered from 1), keeping the findings and
// the timelines drawn.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "ncservo/report/report_charts.hpp"
#include "validator_driver.hpp"

namespace ncservo::test {

struct Recorded {
  std::vector<Finding> findings;
  report::FindingTimelines timelines;
};

// `after_frame`, when given, sees the validator after each frame (its findings are that frame's).
inline Recorded record(const Script& script,
                       const std::function<void(const Validator&)>& after_frame = nullptr,
                       FastPath fast_path = FastPath::On) {
  std::optional<Validator> validator;
  report::TimelineRecorder recorder(script.ruleSettings());
  Recorded out;
  std::uint64_t number = 0;
  std::int64_t first_ns = 0;
  for (std::int64_t k = 0; k < script.cycles(); ++k) {
    for (Copy copy : {Copy::Master, Copy::Returned}) {
      const At at{copy, k};
      const Bytes bytes = scriptFrame(script, at);
      const Walked w = walk(bytes);
      if (!validator) {
        DecoderOptions options = defaultLayoutOf(*w.frame, DecoderOptions{});
        for (std::size_t a = 0; a < options.axes.size() && script.firstStation(); ++a) {
          options.axes[a].station = static_cast<std::uint16_t>(*script.firstStation() + a);
        }
        validator.emplace(options, script.ruleSettings(), fast_path);
        first_ns = script.timeOf(at);
      }
      const Observation& frame =
          validator->onFrame(++number, script.timeOf(at), *w.frame, w.reader());
      recorder.frame(number, script.timeOf(at) - first_ns, frame);
      for (const Finding& f : validator->findings()) {
        out.findings.push_back(f);
        recorder.finding(f);
      }
      if (after_frame) after_frame(*validator);
    }
  }
  out.timelines = recorder.finish();
  return out;
}

// The number record() gives a copy of a cycle.
inline std::uint64_t recordedFrame(At at) {
  return 2 * static_cast<std::uint64_t>(at.cycle) + (at.copy == Copy::Master ? 1 : 2);
}

}  // namespace ncservo::test
