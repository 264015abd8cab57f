#include "ncservo/layout/layout_fit.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "ncservo/base/little_endian.hpp"
#include "ncservo/protocol/pdo_layout.hpp"

namespace ncservo {

namespace {

// Data that fails the signature in at least this share of cycles does not fit; a servo of the
// protocol fails it only while faulty or stale, in a few cycles.
constexpr double kMisfitShare = 0.5;
// A check named in the warning fails in at least this share.
constexpr double kNamedShare = 0.1;
// Fewer cycles than this say nothing.
constexpr std::uint64_t kMinCycles = 16;

int percent(std::uint64_t part, std::uint64_t whole) {
  return static_cast<int>(100.0 * part / whole + 0.5);
}

}  // namespace

void LayoutFit::onFrame(const FrameDecode& decode, const ByteReader& bytes) {
  for (std::size_t i = 0; i < decode.axis_count; ++i) {
    const AxisPlacement& p = decode.axes[i];
    if (p.axis >= axes_.size()) axes_.resize(p.axis + 1);
    AxisTally& axis = axes_[p.axis];
    auto checked = [](Tally& tally) {
      const std::uint64_t n = tally.seen++;
      return n < kEveryCycle || n % kSampleEvery == 0;
    };
    auto count = [](Tally& tally, std::uint32_t failures) {
      ++tally.cycles;
      if (failures != 0) ++tally.failed;
      for (int c = 0; c < kSignatureChecks; ++c) {
        if ((failures & (1u << c)) != 0) ++tally.by_check[c];
      }
    };
    if (p.has_tx && !p.tx_malformed && bytes.has(p.tx_offset, kTxPdoSize) && checked(axis.tx)) {
      const std::uint8_t* pdo = bytes.data() + p.tx_offset;
      const std::uint32_t failures = txSignatureFailures(pdo);
      if ((failures & kMessageCodeUndefined) != 0 && !axis.tx.undefined_code) {
        axis.tx.undefined_code =
            static_cast<std::int32_t>(loadLe<4>(pdo + wordOffset(Word::MsgCode)));
      }
      count(axis.tx, failures);
    }
    if (p.has_rx && !p.rx_malformed && bytes.has(p.rx_offset, kRxPdoSize) && checked(axis.rx)) {
      count(axis.rx, rxSignatureFailures(bytes.data() + p.rx_offset));
    }
  }
}

std::vector<std::string> LayoutFit::warnings(const std::vector<AxisInfo>& axes) const {
  std::vector<std::string> lines;
  for (std::size_t a = 0; a < axes_.size() && a < axes.size(); ++a) {
    const AxisInfo& info = axes[a];
    for (const Pdo pdo : {Pdo::Tx, Pdo::Rx}) {
      const Tally& t = pdo == Pdo::Tx ? axes_[a].tx : axes_[a].rx;
      if (t.cycles < kMinCycles || t.failed < kMisfitShare * t.cycles) continue;
      std::vector<std::string> failed;
      for (int c = 0; c < kSignatureChecks; ++c) {
        if (t.by_check[c] < kNamedShare * t.cycles) continue;
        const std::uint32_t check = 1u << c;
        const std::string what = check == kMessageCodeUndefined && t.undefined_code
                                     ? fmt::format("message code {} outside 0..{}",
                                                   *t.undefined_code, kMaxListedMessageCode)
                                     : signatureCheckName(check);
        failed.push_back(fmt::format("{} in {} % of {} cycles checked", what,
                                     percent(t.by_check[c], t.cycles), t.cycles));
      }
      if (failed.empty()) {
        failed.push_back(fmt::format("some check failing in {} % of {} cycles checked",
                                     percent(t.failed, t.cycles), t.cycles));
      }
      const bool tx = pdo == Pdo::Tx;
      const std::string where =
          info.logical ? fmt::format("{} 0x{:08X}", tx ? "inputs" : "outputs",
                                     tx ? info.inputs : info.outputs)
                       : fmt::format("station 0x{:04X} {} 0x{:04X}", info.station,
                                     tx ? "SM3" : "SM2", tx ? info.sm_inputs : info.sm_outputs);
      lines.push_back(fmt::format(
          "{}: the data at {} does not look like this protocol's {}: {} (docs/layout.md#a-layout-"
          "that-does-not-fit)",
          info.name, where, tx ? "TxPDO" : "RxPDO", fmt::join(failed, ", ")));
    }
  }
  return lines;
}

}  // namespace ncservo
