// `decode --format vcd`: the process data as an IEEE 1364 value change dump for GTKWave
// (docs/waveforms.md), and a GTKWave save file that opens each axis's handshake signals. The
// signals are the field table's rows; only value changes are written, so memory stays constant.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "ncservo/base/error.hpp"
#include "ncservo/layout/decoder.hpp"
#include "ncservo/protocol/drive_state.hpp"
#include "ncservo/protocol/fields.hpp"
#include "ncservo/report/chunk_queue.hpp"
#include "ncservo/rules/finding.hpp"
#include "ncservo/rules/validator.hpp"

namespace ncservo::report {

// The identifier code of the n-th variable: printable ASCII '!'..'~' (IEEE 1364 §18.2.1),
// every one-character code before the first two-character one.
std::string vcdIdCode(std::size_t n);

// A vector's value: 'b' and its binary digits without leading zeros (a VCD reader extends with
// zeros), e.g. "b101"; a scalar's is one digit.
void appendVcdBits(std::string& out, std::uint64_t bits, unsigned width);
// A real's value: 'r' and the shortest text that reads back as the same float.
void appendVcdReal(std::string& out, float value);
// A string's value: 's' and the text with whitespace as '_' (a VCD token has none); the empty
// string is "\000", which GTKWave draws as a line at mid level, like high-Z.
void appendVcdString(std::string& out, std::string_view text);

enum class VcdVarKind : std::uint8_t { Wire, Integer, Real, String };

// One variable of an axis's scope, from one row of the field table.
struct VcdSignal {
  const FieldDef* field;
  VcdVarKind kind;
  unsigned width;
  std::string scope;  // the word's scope for a word with bit fields, else empty
  std::string name;   // the filter name's last part ("se" for ncservo.scw.se)
};
// Every row of the field table, in table order.
const std::vector<VcdSignal>& vcdSignals();

// The scope name of each axis: its name with characters a VCD or GTKWave path cannot hold as
// '_', unique (a clash gets "_INDEX"), never "bus".
std::vector<std::string> vcdScopeNames(const std::vector<AxisInfo>& axes);

// Writes a capture's waveforms frame by frame. The header is written once the layout has placed
// an axis (a start-up teaches the axes before the cyclic traffic begins). The caller's thread
// finds the value changes and hands them over as compact records; a thread of the writer's own
// turns them into text and writes it (docs/benchmarks.md).
class WaveformWriter {
 public:
  // `wanted`: the axes to write, by name or index (decode --axis); empty: every axis.
  // `out_name` names `out` in a write error.
  WaveformWriter(std::FILE* out, std::string out_name, std::vector<std::string> wanted);
  ~WaveformWriter();
  WaveformWriter(const WaveformWriter&) = delete;
  WaveformWriter& operator=(const WaveformWriter&) = delete;

  // One frame as the validator judged it; `time_ns` is since the capture's first frame. A frame
  // whose time goes back is written at the latest time. Master copies give the outputs and
  // returned copies the inputs, each at its own time; a returned copy gives the outputs too where
  // no master copy of them was captured. Fails once a write has failed.
  Status frame(std::int64_t time_ns, const Observation& frame, const Decoder& decoder);
  // The findings reported on the frame just written (or at the end of the capture), shown at
  // `time_ns` on their axis's findings signal or the bus's; those before the first axis was
  // placed are kept for the header.
  Status findings(std::int64_t time_ns, const std::vector<Finding>& findings);
  // The capture ended at `end_ns` (since its first frame): the rest is written and the file
  // flushed. Fails with the first failure, the header's or a write's.
  Status finish(std::int64_t end_ns, const Decoder& decoder);

  // The written scopes: "bus", then one per selected axis. Known after the header.
  struct Scope {
    std::string name;
    std::optional<std::uint16_t> axis;  // none for the bus
  };
  const std::vector<Scope>& scopes() const { return scopes_; }
  // The clock that times the frames (docs/timing.md#the-clock), said in the header's comment;
  // before the first frame.
  void timedBy(std::string clock) { clock_ = std::move(clock); }

 private:
  struct Value {
    std::uint64_t bits = 0;
    bool known = false;
  };
  struct AxisSlot {
    std::size_t first_id = 0;
    std::vector<Value> values;                      // by vcdSignals() index
    std::array<std::uint64_t, kWordCount> words{};  // as last written
    std::array<bool, kWordCount> word_known{};
    std::optional<DriveState> state;
    bool outputs_from_master = false;  // a master copy gave the outputs since the last return
    std::string findings;              // the rule IDs shown at the current time
  };
  struct SignalRange {
    std::size_t begin = 0, end = 0;
    bool conditional = false;  // one of them is (SignalBits::conditional)
  };
  // How a signal's bits come out of its word, worked out once (the hot path): a float's own
  // bits, an integer's two's complement of its width (as fieldValue's value, masked to the width).
  struct SignalBits {
    std::uint64_t mask;  // the word's bits it shows: a change in no other bit changes it
    unsigned shift;
    std::uint64_t width_mask;
    std::size_t word;  // index in PdoValues::raw
    bool conditional;  // shown under a condition (fieldApplies), not only when its PDO is there
    bool scalar;
    bool real;
  };
  static std::array<SignalRange, kWordCount> signalsOfWords();
  static SignalBits signalBitsOf(const VcdSignal& signal);
  Status writeHeader(const Decoder& decoder);
  void advance(std::int64_t time_ns);
  void stamp();
  void writeWords(AxisSlot& slot, const PdoValues& values, Pdo pdo);
  void writeSignal(AxisSlot& slot, std::size_t signal, const PdoValues& values);
  void writeState(AxisSlot& slot, std::optional<DriveState> state);
  AxisSlot* findingSlot(std::optional<std::uint16_t> axis);
  const std::string& findingsId(const AxisSlot& slot) const;
  void showFinding(AxisSlot& slot, std::string_view rule);
  void clearFindings(AxisSlot& slot);
  // The records for the text writer: value changes go straight into the chunk (room), text
  // through put().
  char* room(std::size_t size);
  void put(std::string_view text);
  void putString(std::string_view text);
  void handOver();
  Status closeText();

  std::FILE* out_;
  std::string out_name_;
  std::vector<std::string> wanted_;
  const std::vector<VcdSignal>& signals_;                    // vcdSignals()
  const std::array<SignalRange, kWordCount> signal_ranges_;  // each word's, in signals_
  std::vector<SignalBits> signal_bits_;                      // by signals_ index
  bool header_written_ = false;
  std::vector<Scope> scopes_;
  std::string clock_;
  AxisSlot bus_;
  std::vector<AxisSlot> axes_;           // by scope order after the bus
  std::vector<std::ptrdiff_t> slot_of_;  // by axis index: index in axes_, or -1
  std::vector<std::string> ids_;         // by variable number
  std::int64_t time_ns_ = 0;
  bool time_written_ = false;
  bool findings_shown_ = false;
  // Findings before the header (a start-up's), written once it is: bounded.
  struct EarlyFinding {
    std::int64_t time_ns;
    std::optional<std::uint16_t> axis;
    const char* rule;
  };
  static constexpr std::size_t kMaxEarlyFindings = 4096;
  std::vector<EarlyFinding> early_findings_;
  std::size_t early_findings_dropped_ = 0;
  ChunkQueue queue_;
  ChunkQueue::Chunk records_;
  Status handed_over_;   // the first failure to hand records over: the text writer stopped
  Status text_written_;  // the text writer's, read once it has ended
  std::thread text_writer_;
};

// A GTKWave save file for `vcd_path`, to be written at `save_path` (GTKWave looks for the VCD
// beside it when the path no longer holds: the two files can move together). Per scope a group of
// the signals the drive state and the handshakes are judged on (the axis model's declared reads),
// the drive state and the findings.
void writeGtkwSave(std::FILE* out, const std::string& vcd_path, const std::string& save_path,
                   const std::vector<WaveformWriter::Scope>& scopes);

// OUT.vcd -> OUT.gtkw (any other name gets ".gtkw" added).
std::string gtkwPathFor(const std::string& vcd_path);

}  // namespace ncservo::report
