#include "ncservo/coverage.hpp"

#include <fmt/format.h>

namespace ncservo {

Coverage coverageOf(const Validator& validator) {
  Coverage out;
  const Decoder& decoder = validator.decoder();
  const bool configured =
      decoder.source() == LayoutSource::Config || decoder.source() == LayoutSource::Eni;
  for (const AxisInfo& info : decoder.axes()) {
    if (validator.axis(info.index) != nullptr) {
      out.any_axis = true;
    } else if (configured) {
      out.missing.push_back(info.name);
    }
  }
  if (decoder.axes().empty()) {
    out.reason = decoder.noServoReason();
  } else if (!out.any_axis) {
    out.reason = fmt::format(
        "no servo axis decoded: none of the {} ax{} of the {} layout "
        "appeared in the capture",
        decoder.axes().size(), decoder.axes().size() == 1 ? "is" : "es",
        layoutSourceName(decoder.source()));
  } else if (!out.missing.empty()) {
    out.reason = fmt::format("configured ax{} never in the capture: {}",
                             out.missing.size() == 1 ? "is" : "es", fmt::join(out.missing, ", "));
  }
  return out;
}

}  // namespace ncservo
