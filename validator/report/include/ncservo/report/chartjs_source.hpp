// Chart.js (Debian's libjs-chart.js, MIT), as the HTML report inlines it: generated at build time
// from the package's chart.min.js by embed_file.cmake.
#pragma once

#include <cstddef>

namespace ncservo::report {
extern const char kChartJs[];
extern const std::size_t kChartJsSize;
}  // namespace ncservo::report
