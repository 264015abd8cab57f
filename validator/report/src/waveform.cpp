#include "ncservo/report/waveform.hpp"

#include <fmt/compile.h>
#include <fmt/format.h>

#include <algorithm>
#include <cstring>

#include "ncservo/model/axis_model.hpp"
#include "ncservo/report/axis_selection.hpp"
#include "ncservo/rules/rules.hpp"

namespace ncservo::report {

namespace {

constexpr char kFirstIdChar = '!';
constexpr std::size_t kIdChars = '~' - '!' + 1;
constexpr std::string_view kBusScope = "bus";
// The text is written in pieces of about this size.
constexpr std::size_t kFlushAt = 1u << 16;
// The records handed to the text writer: a few large chunks in flight keep both threads busy
// with little locking, and the memory bounded.
constexpr std::size_t kChunkBytes = 1u << 20;
constexpr std::size_t kChunksInFlight = 4;

std::string_view shortName(const FieldDef& f) {
  return std::string_view(f.filter).substr(std::strlen("ncservo."));
}

constexpr unsigned highestBit(std::uint64_t mask) {
  unsigned bit = 63;
  while (bit > 0 && !((mask >> bit) & 1)) --bit;
  return bit;
}

bool wordHasBitFields(Word word) {
  return std::any_of(std::begin(kFields), std::end(kFields), [&](const FieldDef& f) {
    return f.word == word && f.kind != FieldKind::Word;
  });
}

VcdSignal signalOf(const FieldDef& f) {
  const WordDef& word = wordDef(f.word);
  const std::string_view name = shortName(f);
  const std::size_t dot = name.find('.');
  VcdSignal s{&f, VcdVarKind::Wire, 1, "", std::string(name.substr(dot + 1))};
  if (dot != std::string_view::npos) {
    s.scope = std::string(name.substr(0, dot));
  } else if (wordHasBitFields(f.word)) {
    s.scope = s.name;
  }
  switch (f.kind) {
    case FieldKind::Word:
      s.kind = word.type == WireType::F32   ? VcdVarKind::Real
               : word.type == WireType::U32 ? VcdVarKind::Wire
                                            : VcdVarKind::Integer;
      s.width = s.kind == VcdVarKind::Real ? 64u : 8u * word.size;  // a VCD real is a double
      break;
    case FieldKind::Part:
      s.kind = VcdVarKind::Integer;
      s.width = static_cast<unsigned>(popcount64(f.mask));
      break;
    case FieldKind::Flag:
    case FieldKind::BitRange:
      // As fieldValue shows it: shifted down to its lowest bit, gaps kept (SEW's reserved bits).
      s.width = highestBit(f.mask) - lowestBit(f.mask) + 1u;
      break;
  }
  return s;
}

const char* varKeyword(VcdVarKind kind) {
  switch (kind) {
    case VcdVarKind::Wire:
      return "wire";
    case VcdVarKind::Integer:
      return "integer";
    case VcdVarKind::Real:
      return "real";
    case VcdVarKind::String:
      return "string";
  }
  return "wire";
}

// The name GTKWave gives the variable: a wire vector carries its declared range.
std::string declaredName(const std::string& name, VcdVarKind kind, unsigned width) {
  return kind == VcdVarKind::Wire && width > 1 ? fmt::format("{} [{}:0]", name, width - 1) : name;
}

// The variables of an axis after the field table's: the drive state and the findings.
constexpr std::size_t kStateVar = 0;
constexpr std::size_t kFindingsVar = 1;
constexpr std::size_t kDerivedVars = 2;

}  // namespace

std::string vcdIdCode(std::size_t n) {
  std::string id;
  do {
    id.push_back(static_cast<char>(kFirstIdChar + n % kIdChars));
    n /= kIdChars;
  } while (n-- != 0);
  return id;
}

namespace {
// The longest value line: 'b', 64 digits, a space, an identifier code and the newline.
constexpr std::size_t kMaxValueLine = 1 + 64 + 1 + 8 + 1;

// A vector's value at `out`; returns the end. The digits come eight at a time from a table: the
// hot path of ActPos, which changes every cycle.
char* writeVcdVector(char* out, std::uint64_t bits) {
  static const auto kDigits = [] {
    std::array<std::array<char, 8>, 256> table{};
    for (unsigned byte = 0; byte < 256; ++byte) {
      for (unsigned bit = 0; bit < 8; ++bit) table[byte][7 - bit] = (byte >> bit) & 1 ? '1' : '0';
    }
    return table;
  }();
  *out++ = 'b';
  const unsigned digits = bits == 0 ? 1u : 64u - static_cast<unsigned>(__builtin_clzll(bits));
  unsigned shift = (digits - 1) / 8 * 8;
  const unsigned lead = digits - shift;  // digits of the highest byte written
  std::memcpy(out, kDigits[(bits >> shift) & 0xFF].data() + 8 - lead, lead);
  out += lead;
  while (shift != 0) {
    shift -= 8;
    std::memcpy(out, kDigits[(bits >> shift) & 0xFF].data(), 8);
    out += 8;
  }
  return out;
}

// A vector's or scalar's value at `out`; returns the end.
char* writeVcdBits(char* out, std::uint64_t bits, unsigned width) {
  if (width == 1) {
    *out++ = (bits & 1) != 0 ? '1' : '0';
    return out;
  }
  return writeVcdVector(out, bits);
}

// A real's value at `out` (at most 1 + 16 characters); returns the end.
char* writeVcdReal(char* out, float value) {
  *out++ = 'r';
  return fmt::format_to(out, FMT_COMPILE("{}"), value);
}

// What the walking thread hands the text writer: a kind, then its fields, unaligned. A value
// record names its variable by number (the identifier code's n).
enum class Record : char {
  Time,           // std::int64_t ns: "#TIME"
  Vector,         // std::uint32_t variable, std::uint64_t bits
  Scalar,         // std::uint32_t variable, std::uint64_t bits (the lowest)
  Real,           // std::uint32_t variable, float
  UnknownVector,  // std::uint32_t variable
  UnknownScalar,  // std::uint32_t variable
  Text,           // std::uint32_t size, the text
};
constexpr std::size_t kMaxValueRecord = 1 + 4 + 8;
constexpr std::size_t kTextRecordHead = 1 + 4;

template <class T>
char* store(char* at, T value) {
  std::memcpy(at, &value, sizeof value);
  return at + sizeof value;
}
template <class T>
const char* load(const char* at, T& value) {
  std::memcpy(&value, at, sizeof value);
  return at + sizeof value;
}

// The text writer's side: records into VCD text, written to the file.
class VcdText {
 public:
  explicit VcdText(std::FILE* out, const std::string& out_name)
      : out_(out), out_name_(out_name), text_(kFlushAt + kMaxValueLine) {}

  Status write(const ChunkQueue::Chunk& chunk) {
    const char* at = chunk.bytes.data();
    const char* const end = at + chunk.used;
    while (at < end) {
      Record kind;
      at = load(at, kind);
      if (kind == Record::Text) {
        std::uint32_t size;
        at = load(at, size);
        if (Status put = putText(std::string_view(at, size)); !put) return put;
        at += size;
        continue;
      }
      char* line = text_.data() + used_;
      if (kind == Record::Time) {
        std::int64_t time_ns;
        at = load(at, time_ns);
        const fmt::format_int digits(time_ns);
        *line++ = '#';
        line = std::copy_n(digits.data(), digits.size(), line);
        *line++ = '\n';
      } else {
        std::uint32_t variable;
        at = load(at, variable);
        switch (kind) {
          case Record::Vector:
          case Record::Scalar: {
            std::uint64_t bits;
            at = load(at, bits);
            line = writeVcdBits(line, bits, kind == Record::Scalar ? 1 : 64);
            if (kind == Record::Vector) *line++ = ' ';
            break;
          }
          case Record::Real: {
            float value;
            at = load(at, value);
            line = writeVcdReal(line, value);
            *line++ = ' ';
            break;
          }
          case Record::UnknownVector:
            line = std::copy_n("bx ", 3, line);
            break;
          default:
            *line++ = 'x';
            break;
        }
        for (char c : idOf(variable)) *line++ = c;
        *line++ = '\n';
      }
      used_ = static_cast<std::size_t>(line - text_.data());
      if (used_ >= kFlushAt) {
        if (Status flushed = flush(); !flushed) return flushed;
      }
    }
    return {};
  }

  // The rest of the text, and the file's buffer.
  Status finish() {
    if (Status flushed = flush(); !flushed) return flushed;
    if (std::fflush(out_) != 0) return writeFailed();
    return {};
  }

 private:
  Status putText(std::string_view text) {
    if (used_ + text.size() > text_.size()) {
      if (Status flushed = flush(); !flushed) return flushed;
    }
    if (text.size() > text_.size()) return writeOut(text);
    std::memcpy(text_.data() + used_, text.data(), text.size());
    used_ += text.size();
    return {};
  }

  Status flush() {
    const Status written = writeOut(std::string_view(text_.data(), used_));
    used_ = 0;
    return written;
  }

  Status writeOut(std::string_view text) {
    if (std::fwrite(text.data(), 1, text.size(), out_) != text.size()) return writeFailed();
    return {};
  }

  Status writeFailed() const {
    Error error{out_name_, 0, 0, {}, fmt::format("cannot write: {}", std::strerror(errno))};
    return fail(std::move(error));
  }

  // Identifier codes by variable number, made as first needed.
  const std::string& idOf(std::uint32_t variable) {
    while (ids_.size() <= variable) ids_.push_back(vcdIdCode(ids_.size()));
    return ids_[variable];
  }

  std::FILE* out_;
  const std::string& out_name_;
  std::vector<char> text_;
  std::size_t used_ = 0;
  std::vector<std::string> ids_;
};

// The text writer's thread: every chunk in order until the queue closes, or the first failure,
// which stops the queue too.
Status writeVcdText(ChunkQueue& queue, std::FILE* out, const std::string& out_name) {
  VcdText text(out, out_name);
  while (std::optional<ChunkQueue::Chunk> chunk = queue.pop()) {
    if (Status written = text.write(*chunk); !written) {
      queue.stop(written.error());
      return written;
    }
    queue.recycle(std::move(*chunk));
  }
  Status finished = text.finish();
  if (!finished) queue.stop(finished.error());
  return finished;
}
}  // namespace

void appendVcdBits(std::string& out, std::uint64_t bits, unsigned width) {
  char text[kMaxValueLine];
  out.append(text, writeVcdBits(text, bits, width));
}

void appendVcdReal(std::string& out, float value) {
  char text[32];
  out.append(text, writeVcdReal(text, value));
}

void appendVcdString(std::string& out, std::string_view text) {
  out.push_back('s');
  if (text.empty()) {
    out += "\\000";
    return;
  }
  for (char c : text) out.push_back(c == ' ' || c == '\t' || c == '\n' ? '_' : c);
}

const std::vector<VcdSignal>& vcdSignals() {
  static const std::vector<VcdSignal> signals = [] {
    std::vector<VcdSignal> all;
    for (const FieldDef& f : kFields) all.push_back(signalOf(f));
    return all;
  }();
  return signals;
}

std::vector<std::string> vcdScopeNames(const std::vector<AxisInfo>& axes) {
  std::vector<std::string> names;
  for (const AxisInfo& axis : axes) {
    std::string name = axis.name.empty() ? fmt::format("axis{}", axis.index) : axis.name;
    for (char& c : name) {
      const bool plain = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') ||
                         (c >= '0' && c <= '9') || c == '_' || c == '-';
      if (!plain) c = '_';
    }
    const bool clash =
        name == kBusScope || std::find(names.begin(), names.end(), name) != names.end();
    if (clash) name += fmt::format("_{}", axis.index);
    names.push_back(std::move(name));
  }
  return names;
}

WaveformWriter::SignalBits WaveformWriter::signalBitsOf(const VcdSignal& s) {
  const std::uint64_t mask = s.field->mask;
  const bool real = s.kind == VcdVarKind::Real;
  return {mask == 0 ? ~std::uint64_t{0} : mask,
          mask == 0 ? 0u : lowestBit(mask),
          s.width >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << s.width) - 1,
          static_cast<std::size_t>(s.field->word),
          s.field->when != FieldWhen::Always,
          s.width == 1,
          real};
}

// The signals of each word: the field table holds a word's rows together.
std::array<WaveformWriter::SignalRange, kWordCount> WaveformWriter::signalsOfWords() {
  std::array<SignalRange, kWordCount> out{};
  const std::vector<VcdSignal>& signals = vcdSignals();
  for (std::size_t i = signals.size(); i-- > 0;) {
    SignalRange& range = out[static_cast<std::size_t>(signals[i].field->word)];
    if (range.end == 0) range.end = i + 1;
    range.begin = i;
    range.conditional = range.conditional || signals[i].field->when != FieldWhen::Always;
  }
  return out;
}

WaveformWriter::WaveformWriter(std::FILE* out, std::string out_name,
                               std::vector<std::string> wanted)
    : out_(out),
      out_name_(std::move(out_name)),
      wanted_(std::move(wanted)),
      signals_(vcdSignals()),
      signal_ranges_(signalsOfWords()),
      queue_(kChunksInFlight, kChunkBytes),
      records_(queue_.spare()) {
  for (const VcdSignal& s : signals_) signal_bits_.push_back(signalBitsOf(s));
  text_writer_ = std::thread([this] { text_written_ = writeVcdText(queue_, out_, out_name_); });
}

// Without finish() (a failed header), what was handed over is still written.
WaveformWriter::~WaveformWriter() {
  static_cast<void>(closeText());
}

Status WaveformWriter::writeHeader(const Decoder& decoder) {
  header_written_ = true;
  const std::vector<AxisInfo>& axes = decoder.axes();
  if (Status checked = checkAxisSelection(wanted_, axes); !checked) return checked;
  const std::vector<VcdSignal>& signals = vcdSignals();
  const std::vector<std::string> names = vcdScopeNames(axes);
  scopes_.push_back(Scope{std::string(kBusScope), std::nullopt});
  ids_.push_back(vcdIdCode(0));
  slot_of_.assign(axes.size(), -1);
  for (const AxisInfo& axis : axes) {
    if (!axisSelected(wanted_, axis)) continue;
    slot_of_[axis.index] = static_cast<std::ptrdiff_t>(axes_.size());
    scopes_.push_back(Scope{names[axis.index], axis.index});
    AxisSlot& slot = axes_.emplace_back();
    slot.first_id = ids_.size();
    slot.values.resize(signals.size());
    for (std::size_t i = 0; i < signals.size() + kDerivedVars; ++i) {
      ids_.push_back(vcdIdCode(ids_.size()));
    }
  }

  put(fmt::format("$version ncservo {} $end\n", NCSERVO_VERSION));
  put("$comment layout source: ");
  put(layoutSourceName(decoder.source()));
  put("; time 0 is the capture's first frame");
  if (!clock_.empty()) put("; clock: " + clock_);
  put(" $end\n$timescale 1 ns $end\n");
  put(fmt::format("$scope module {} $end\n$var string 1 {} findings $end\n$upscope $end\n",
                  kBusScope, ids_[0]));
  for (std::size_t a = 0; a < axes_.size(); ++a) {
    const AxisSlot& slot = axes_[a];
    put(fmt::format("$scope module {} $end\n", scopes_[a + 1].name));
    std::string open;
    for (std::size_t i = 0; i < signals.size(); ++i) {
      const VcdSignal& s = signals[i];
      if (s.scope != open) {
        if (!open.empty()) put("$upscope $end\n");
        if (!s.scope.empty()) put(fmt::format("$scope module {} $end\n", s.scope));
        open = s.scope;
      }
      put(fmt::format("$var {} {} {} {} $end\n", varKeyword(s.kind), s.width,
                      ids_[slot.first_id + i], declaredName(s.name, s.kind, s.width)));
    }
    if (!open.empty()) put("$upscope $end\n");
    const std::size_t derived = slot.first_id + signals.size();
    put(fmt::format("$var string 1 {} state $end\n", ids_[derived + kStateVar]));
    put(fmt::format("$var string 1 {} findings $end\n", ids_[derived + kFindingsVar]));
    put("$upscope $end\n");
  }
  put("$enddefinitions $end\n#0\n$dumpvars\n");
  time_written_ = true;
  auto unknown = [&](std::size_t id, VcdVarKind kind, unsigned width) {
    if (kind == VcdVarKind::Real) return;  // a real has no unknown value
    if (kind == VcdVarKind::String) {
      putString("");
    } else {
      put(width == 1 ? "x" : "bx ");
    }
    put(ids_[id]);
    put("\n");
  };
  unknown(0, VcdVarKind::String, 1);
  for (const AxisSlot& slot : axes_) {
    for (std::size_t i = 0; i < signals.size(); ++i) {
      unknown(slot.first_id + i, signals[i].kind, signals[i].width);
    }
    for (std::size_t d = 0; d < kDerivedVars; ++d) {
      unknown(slot.first_id + signals.size() + d, VcdVarKind::String, 1);
    }
  }
  put("$end\n");
  for (const EarlyFinding& f : early_findings_) {
    advance(f.time_ns);
    if (AxisSlot* slot = findingSlot(f.axis)) showFinding(*slot, f.rule);
  }
  if (early_findings_dropped_ != 0) {
    put(fmt::format("$comment {} more findings before the first axis was placed $end\n",
                    early_findings_dropped_));
  }
  early_findings_.clear();
  return {};
}

void WaveformWriter::stamp() {
  if (time_written_) return;
  char* at = room(1 + sizeof time_ns_);
  at = store(at, Record::Time);
  at = store(at, time_ns_);
  records_.used = static_cast<std::size_t>(at - records_.bytes.data());
  time_written_ = true;
}

// Moves to `time_ns` (never back); a finding shown at an earlier time ends there.
void WaveformWriter::advance(std::int64_t time_ns) {
  if (time_ns <= time_ns_) return;
  time_ns_ = time_ns;
  time_written_ = false;
  if (!findings_shown_) return;
  findings_shown_ = false;
  clearFindings(bus_);
  for (AxisSlot& slot : axes_) clearFindings(slot);
}

void WaveformWriter::writeWords(AxisSlot& slot, const PdoValues& values, Pdo pdo) {
  for (std::size_t w = firstWordOf(pdo); w < firstWordOf(pdo) + wordCountOf(pdo); ++w) {
    // A field whose bits did not change keeps the value written (the word's PDO is here, so it
    // applies), but for those shown under another word's condition.
    const std::uint64_t raw = values.raw[w];
    const std::uint64_t changed = slot.word_known[w] ? raw ^ slot.words[w] : ~std::uint64_t{0};
    slot.words[w] = raw;
    slot.word_known[w] = true;
    const SignalRange range = signal_ranges_[w];
    if (changed == 0 && !range.conditional) continue;
    for (std::size_t i = range.begin; i < range.end; ++i) {
      const SignalBits& bits = signal_bits_[i];
      if (bits.conditional || (changed & bits.mask) != 0) writeSignal(slot, i, values);
    }
  }
}

// Called for a PDO that is there: only a conditional field can be unknown.
void WaveformWriter::writeSignal(AxisSlot& slot, std::size_t i, const PdoValues& values) {
  const SignalBits& b = signal_bits_[i];
  const bool known = !b.conditional || fieldApplies(*signals_[i].field, values);
  const std::uint64_t bits = known ? ((values.raw[b.word] & b.mask) >> b.shift) & b.width_mask : 0;
  Value& last = slot.values[i];
  if (known == last.known && bits == last.bits) return;
  last = Value{bits, known};
  stamp();
  // Written straight into the chunk: the hot path.
  char* at = room(kMaxValueRecord);
  const auto variable = static_cast<std::uint32_t>(slot.first_id + i);
  if (!known) {
    at = store(at, b.scalar ? Record::UnknownScalar : Record::UnknownVector);
    at = store(at, variable);
  } else if (b.real) {
    at = store(at, Record::Real);
    at = store(at, variable);
    at = store(at, values.floatOf(static_cast<Word>(b.word)));
  } else {
    at = store(at, b.scalar ? Record::Scalar : Record::Vector);
    at = store(at, variable);
    at = store(at, bits);
  }
  records_.used = static_cast<std::size_t>(at - records_.bytes.data());
}

void WaveformWriter::writeState(AxisSlot& slot, std::optional<DriveState> state) {
  if (state == slot.state) return;
  slot.state = state;
  stamp();
  putString(state ? driveStateName(*state) : "");
  put(ids_[slot.first_id + signals_.size() + kStateVar]);
  put("\n");
}

const std::string& WaveformWriter::findingsId(const AxisSlot& slot) const {
  return &slot == &bus_ ? ids_[0] : ids_[slot.first_id + vcdSignals().size() + kFindingsVar];
}

// Where a finding about `axis` (none: the bus) is shown; null for an axis not written.
WaveformWriter::AxisSlot* WaveformWriter::findingSlot(std::optional<std::uint16_t> axis) {
  if (!axis) return &bus_;
  if (*axis >= slot_of_.size() || slot_of_[*axis] < 0) return nullptr;
  return &axes_[static_cast<std::size_t>(slot_of_[*axis])];
}

// The rule joins those shown at this time on the slot's findings signal.
void WaveformWriter::showFinding(AxisSlot& slot, std::string_view rule) {
  if (!slot.findings.empty()) slot.findings += ',';
  slot.findings += rule;
  findings_shown_ = true;
  stamp();
  putString(slot.findings);
  put(findingsId(slot));
  put("\n");
}

void WaveformWriter::clearFindings(AxisSlot& slot) {
  if (slot.findings.empty()) return;
  slot.findings.clear();
  stamp();
  putString("");
  put(findingsId(slot));
  put("\n");
}

Status WaveformWriter::frame(std::int64_t time_ns, const Observation& frame,
                             const Decoder& decoder) {
  if (!header_written_ && frame.decode.axis_count == 0) return {};
  if (!header_written_) {
    if (Status written = writeHeader(decoder); !written) return written;
  }
  advance(time_ns);
  const FrameDecode& decode = frame.decode;
  const bool returned = decode.copy == CopyKind::Returned;
  for (std::size_t i = 0; i < decode.axis_count; ++i) {
    const AxisPlacement& placement = decode.axes[i];
    if (placement.axis >= slot_of_.size() || slot_of_[placement.axis] < 0) continue;
    AxisSlot& slot = axes_[static_cast<std::size_t>(slot_of_[placement.axis])];
    const PdoValues& values = frame.values[i];
    if (!returned) {
      if (values.has_rx) writeWords(slot, values, Pdo::Rx);
      slot.outputs_from_master = values.has_rx;
    } else {
      if (values.has_rx && !slot.outputs_from_master) writeWords(slot, values, Pdo::Rx);
      if (values.has_tx) writeWords(slot, values, Pdo::Tx);
      slot.outputs_from_master = false;
    }
    writeState(slot, frame.states[i]);
  }
  return handed_over_;
}

Status WaveformWriter::findings(std::int64_t time_ns, const std::vector<Finding>& findings) {
  if (!header_written_) {
    for (const Finding& f : findings) {
      if (early_findings_.size() >= kMaxEarlyFindings) {
        ++early_findings_dropped_;
      } else {
        early_findings_.push_back(EarlyFinding{time_ns, f.axis, ruleDef(f.rule).code});
      }
    }
    return {};
  }
  advance(time_ns);
  for (const Finding& f : findings) {
    if (AxisSlot* slot = findingSlot(f.axis)) showFinding(*slot, ruleDef(f.rule).code);
  }
  return handed_over_;
}

Status WaveformWriter::finish(std::int64_t end_ns, const Decoder& decoder) {
  Status status;
  if (!header_written_) status = writeHeader(decoder);
  advance(end_ns);
  stamp();
  handOver();
  const Status written = closeText();
  return !status ? status : written;
}

char* WaveformWriter::room(std::size_t size) {
  if (records_.used + size > records_.bytes.size()) handOver();
  return records_.bytes.data() + records_.used;
}

// The chunk goes to the text writer; once it has stopped, records are dropped.
void WaveformWriter::handOver() {
  if (records_.used == 0) return;
  if (!handed_over_) {
    records_.used = 0;
    return;
  }
  handed_over_ = queue_.push(std::move(records_));
  records_ = queue_.spare();
}

// The text writer writes what was handed over and ends; its status, or the first failure to
// hand records over (the same failure, seen earlier).
Status WaveformWriter::closeText() {
  if (text_writer_.joinable()) {
    queue_.close();
    text_writer_.join();
  }
  return !handed_over_ ? handed_over_ : text_written_;
}

void WaveformWriter::put(std::string_view text) {
  while (!text.empty()) {
    const std::size_t piece = std::min(text.size(), kChunkBytes - kTextRecordHead);
    char* at = room(kTextRecordHead + piece);
    at = store(at, Record::Text);
    at = store(at, static_cast<std::uint32_t>(piece));
    std::memcpy(at, text.data(), piece);
    records_.used = static_cast<std::size_t>(at + piece - records_.bytes.data());
    text.remove_prefix(piece);
  }
}

// A string variable's value and the space before its identifier code.
void WaveformWriter::putString(std::string_view text) {
  std::string value;
  appendVcdString(value, text);
  value += ' ';
  put(value);
}

std::string gtkwPathFor(const std::string& vcd_path) {
  constexpr std::string_view kVcd = ".vcd";
  if (vcd_path.size() > kVcd.size() &&
      vcd_path.compare(vcd_path.size() - kVcd.size(), kVcd.size(), kVcd) == 0) {
    return vcd_path.substr(0, vcd_path.size() - kVcd.size()) + ".gtkw";
  }
  return vcd_path + ".gtkw";
}

void writeGtkwSave(std::FILE* out, const std::string& vcd_path, const std::string& save_path,
                   const std::vector<WaveformWriter::Scope>& scopes) {
  // GTKWave's trace flags (its analyzer.h): hexadecimal, binary, signed decimal, a blank trace,
  // and the beginning and end of a group.
  constexpr unsigned kHex = 0x22, kBinary = 0x28, kSigned = 0x420;
  constexpr unsigned kGroupBegin = 0x800200, kGroupEnd = 0x1000200;
  const std::vector<VcdSignal>& signals = vcdSignals();
  // What the drive state and the handshakes are judged on: a word read whole is shown as the
  // word, else its bit fields that are read.
  const Reads& reads = AxisModel::kReads;
  std::vector<std::size_t> shown;
  for (std::size_t i = 0; i < signals.size(); ++i) {
    const FieldDef& f = *signals[i].field;
    const std::uint64_t read = reads.bits[static_cast<std::size_t>(f.word)];
    const bool whole = read == wordMask(f.word);
    if (f.kind == FieldKind::Word ? whole : !whole && (read & f.mask) != 0) shown.push_back(i);
  }
  std::string text = fmt::format(
      "[*] ncservo {}: per axis, the signals its drive state and handshakes are judged on\n"
      "[dumpfile] \"{}\"\n[savefile] \"{}\"\n[timestart] 0\n",
      NCSERVO_VERSION, vcd_path, save_path);
  unsigned flags = 0;
  auto trace = [&](unsigned trace_flags, const std::string& line) {
    if (trace_flags != flags) text += fmt::format("@{:x}\n", trace_flags);
    flags = trace_flags;
    text += line + "\n";
  };
  for (const WaveformWriter::Scope& scope : scopes) {
    trace(kGroupBegin, "-" + scope.name);
    if (scope.axis) {
      for (std::size_t i : shown) {
        const VcdSignal& s = signals[i];
        const std::string path =
            scope.name + "." + (s.scope.empty() ? "" : s.scope + ".") + s.name +
            (s.kind == VcdVarKind::Wire && s.width > 1 ? fmt::format("[{}:0]", s.width - 1) : "");
        trace(s.kind == VcdVarKind::Integer ? kSigned : s.width == 1 ? kBinary : kHex, path);
      }
      trace(kBinary, scope.name + ".state");
    }
    trace(kBinary, scope.name + ".findings");
    trace(kGroupEnd, "-" + scope.name);
  }
  std::fputs(text.c_str(), out);
}

}  // namespace ncservo::report
