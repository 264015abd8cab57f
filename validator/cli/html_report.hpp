// `validate --format html`: one self-contained page (INTERFACES.md) with the verdict and counts,
// a findings table that sorts and filters, each drawn finding's bit timeline, each axis's state
// timeline and error history, and the cycle-time histogram. Chart.js (Debian's libjs-chart.js) is
// inlined at build time: the page fetches nothing when it opens.
#pragma once

#include <cstddef>
#include <vector>

#include "report.hpp"

namespace ncservo::cli {

// The findings listed in the table, per capture; past it the page says how many were left out.
inline constexpr std::size_t kHtmlMaxTableRows = 20000;

void writeHtml(const ReportSink& sink, const std::vector<CaptureReport>& reports);

}  // namespace ncservo::cli
