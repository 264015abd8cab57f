#include "ncservo/rules/coverage.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

namespace ncservo {

namespace {
// Whether the rule reads any word of the PDO.
bool readsPdo(const RuleDef& rule, Pdo pdo) {
  for (const WordDef& word : kWords) {
    const auto w = static_cast<std::size_t>(word.word);
    if (word.pdo == pdo && (rule.reads.bits[w] != 0 || rule.reads.classes[w] != nullptr)) {
      return true;
    }
  }
  return false;
}

// The axis rules whose words the capture never gave for this axis.
void notJudgedOnAxis(const Validator& validator, const AxisModel& axis,
                     std::vector<NotJudged>& out) {
  for (const RuleDef& rule : kRules) {
    if (rule.kind != RuleKind::Axis || !validator.settings().isEnabled(rule.id)) continue;
    const bool no_outputs = readsPdo(rule, Pdo::Rx) && !axis.sawOutputs();
    const bool no_inputs = readsPdo(rule, Pdo::Tx) && !axis.sawInputs();
    if (!no_outputs && !no_inputs) continue;
    out.push_back({rule.id, axis.index(),
                   fmt::format("its {} never captured",
                               no_outputs && no_inputs ? "outputs (RxPDO) and inputs (TxPDO) were"
                               : no_outputs            ? "outputs (RxPDO) were"
                                                       : "inputs (TxPDO) were")});
  }
}
}  // namespace

Coverage coverageOf(const Validator& validator) {
  Coverage out;
  const Decoder& decoder = validator.decoder();
  const bool configured =
      decoder.source() == LayoutSource::Config || decoder.source() == LayoutSource::Eni;
  bool placed = false;  // some axis was placed, though its words may all have been cut off
  for (const AxisInfo& info : decoder.axes()) {
    const AxisModel* axis = validator.axis(info.index);
    placed = placed || axis != nullptr;
    if (axis != nullptr) notJudgedOnAxis(validator, *axis, out.not_judged);
    if (axis != nullptr && (axis->sawOutputs() || axis->sawInputs())) {
      out.any_axis = true;
    } else if (configured) {
      out.missing.push_back(info.name);
    }
  }
  const BusModel& bus = validator.bus();
  if (bus.uncapturedWkcs() > 0 && validator.settings().isEnabled(RuleId::Com001)) {
    out.not_judged.push_back(
        {RuleId::Com001, std::nullopt,
         fmt::format("the working counter of {} returned datagram{} with servo PDOs was not "
                     "captured (first: frame {}); COM-003 and COM-005 count no failure there",
                     bus.uncapturedWkcs(), bus.uncapturedWkcs() == 1 ? "" : "s",
                     bus.firstUncapturedWkcFrame())});
  }
  if (decoder.axes().empty()) {
    out.reason = decoder.noServoReason();
    out.wants_layout = decoder.noServoWantsLayout();
  } else if (!out.any_axis && placed) {
    out.reason = fmt::format(
        "no servo axis decoded: the {} layout's axes appeared, but none of their PDO words was "
        "captured whole (a snap length?)",
        layoutSourceName(decoder.source()));
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
