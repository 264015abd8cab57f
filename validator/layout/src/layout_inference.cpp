#include "ncservo/layout/layout_inference.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <array>
#include <bit>
#include <bitset>
#include <cmath>
#include <cstring>
#include <iterator>
#include <limits>
#include <numeric>
#include <optional>

#include "ncservo/base/little_endian.hpp"
#include "ncservo/protocol/fields.hpp"
#include "ncservo/protocol/pdo_layout.hpp"

namespace ncservo {

namespace {

// The signature of docs/protocol.md §1–5, from the field table.
constexpr std::uint32_t kScwReserved = mask32("ncservo.scw.reserved");
constexpr std::uint32_t kScwSe = mask32("ncservo.scw.se");
constexpr std::uint32_t kSeEnabled = 0x2;  // §2
constexpr std::uint32_t kScwErrorClear = mask32("ncservo.scw.error_clear");
constexpr std::uint32_t kScwZPulseRequest = mask32("ncservo.scw.zpulse_request");
constexpr std::uint32_t kSswReserved = mask32("ncservo.ssw.reserved");
constexpr std::uint32_t kSswStatus = ~kSswReserved;
constexpr std::uint32_t kSswServoEn = mask32("ncservo.ssw.servo_en");
constexpr std::uint32_t kSswErrClearAck = mask32("ncservo.ssw.err_clear_ack");
constexpr std::uint32_t kSswServoRdy = mask32("ncservo.ssw.servo_rdy");
constexpr std::uint32_t kSswZPulseAck = mask32("ncservo.ssw.zpulse_ack");
constexpr std::uint32_t kSewReserved = mask32("ncservo.sew.reserved");
constexpr std::uint32_t kSewSummary = kSewSummaryMask;
constexpr std::uint32_t kSewCauses = kSewCauseMask;
// §5: the codes listed, with a meaning or not (MSG-001 warns of those without).
constexpr auto kMaxMessageCode = static_cast<std::int32_t>(kLastListedMessageCode);
// The largest magnitude of the message datum a drive plausibly sends for each code with a meaning
// (§5: rpm, A, %, V, °C, kW); an undefined code's datum only has to be finite.
constexpr float kMessageDataBound[] = {1e5f, 1e4f, 1e4f, 1e4f, 1e3f, 1e4f};
static_assert(std::size(kMessageDataBound) == kLastDefinedMessageCode + 1,
              "one bound per message code with a meaning");
// A position that moves by more than this many counts per cycle more than it did the cycle
// before is not a position.
constexpr std::int64_t kMaxPositionStep = std::int64_t{1} << 22;
// A mismatch tolerated per this many observations (stale inputs, faults the rules report).
constexpr std::uint32_t kToleranceDivisor = 32;
// ServoEn may stay 1 this many cycles after SE left 0x2 (the drive's disable delay).
constexpr std::uint32_t kDisableLag = 32;
// Cycles of SE 0x2 with ServoEn 1 that make a pair.
constexpr std::uint32_t kMinAgreement = 8;
// A disagreement outweighs this many agreements.
constexpr std::int64_t kDisagreementWeight = 8;
// Below this confidence an axis is ambiguous.
constexpr double kMinConfidence = 0.25;
// Parameter table changes a drive may refuse (the SSW's table not following the SCW's).
constexpr std::uint32_t kRefusedTableChanges = 2;
// A drive's parameter table changes when the NC commands it, seconds apart: a table change beyond
// the refused ones outweighs this many cycles of evidence (a word whose table bits change every
// few dozen cycles is a counter or a measured value).
constexpr std::int64_t kTableChangeWeight = 128;
// Evidence in at least this many cycles before a candidate counts.
constexpr std::uint32_t kMinObservations = 8;

std::uint32_t le32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(loadLe<4>(p));
}

// A float32 a drive would send: finite and not denormal.
bool plausibleFloat(std::uint32_t bits) {
  const std::uint32_t exponent = (bits >> 23) & 0xFF;
  const std::uint32_t mantissa = bits & 0x7FFFFF;
  return exponent != 0xFF && (exponent != 0 || mantissa == 0);
}

bool plausibleMessageData(std::int32_t code, std::uint32_t bits) {
  if (!messageCodeDefined(code)) return true;
  float value;
  std::memcpy(&value, &bits, sizeof value);
  return std::fabs(value) <= kMessageDataBound[code];
}

// ServoRDY as the ready table gives it in either Servo_Ready_Mode (§5).
bool readyPerTable(std::uint32_t ssw, std::uint32_t sew) {
  const bool ready = (ssw & kSswServoRdy) != 0;
  const bool enabled = (ssw & kSswServoEn) != 0;
  const bool errors = (sew & kSewSummary) != 0;
  return ready == !errors || ready == (enabled && !errors);
}

// One bit per parameter table (1..8) that a SCW commands or a SSW shows.
std::uint8_t tableBit(Word word, std::uint32_t value) {
  return static_cast<std::uint8_t>(1u << (parameterTable(word, value) - 1));
}

void noteTable(std::uint8_t table, std::uint8_t& tables, std::uint8_t& last,
               std::uint32_t& changes) {
  if (last != 0 && table != last) ++changes;
  tables |= table;
  last = table;
}

// One bit per cycle, allocated on the first set bit.
struct CycleBits {
  std::vector<std::uint64_t> words;
  void set(std::uint32_t cycle, std::size_t& bytes) {
    const std::size_t word = cycle / 64;
    if (word >= words.size()) {
      bytes += (word + 1 - words.size()) * sizeof(std::uint64_t);
      words.resize(word + 1, 0);
    }
    words[word] |= std::uint64_t{1} << (cycle % 64);
  }
  std::uint64_t word(std::size_t i) const { return i < words.size() ? words[i] : 0; }
  bool any() const { return !words.empty(); }
};

std::uint32_t popcount(std::uint64_t v) {
  return static_cast<std::uint32_t>(std::bitset<64>(v).count());
}

struct RxCandidate {
  std::uint32_t seen = 0;
  std::uint32_t violations = 0;
  std::uint32_t active = 0;  // cycles with a non-zero SCW
  // The control word changes on events (an enable, an error clear), never every cycle like a
  // counter or a terminal's inputs: cycles in which it changed again right after a change.
  std::uint32_t scw_flaps = 0;
  bool scw_changed = false;  // in the cycle before
  std::uint32_t last_scw = 0;
  // The extra data code word selects what the drive sends: it changes now and then, never
  // every cycle like a counter or a terminal's inputs.
  std::uint32_t ext_code_flaps = 0;
  bool ext_code_changed = false;
  std::uint16_t last_ext_code = 0;
  std::uint8_t tables = 0;  // parameter tables commanded
  std::uint8_t last_table = 0;
  std::uint32_t table_changes = 0;
  CycleBits enabled;  // SE 0x2
  CycleBits clear;    // ErrorClear
  CycleBits zpulse;   // ZPulseRequest
};

// The TxPDO signature's independent checks (docs/layout.md).
enum TxCheck : std::size_t {
  kCheckSswReserved,
  kCheckSew,  // reserved bits, summary bit with any cause
  kCheckMessage,
  kCheckFloats,
  kCheckPosition,
  kTxCheckCount,
};

struct TxCandidate {
  std::uint32_t seen = 0;
  std::uint32_t violations = 0;
  std::uint32_t moves = 0;
  std::uint32_t status = 0;
  std::uint32_t last_position = 0;
  std::int64_t last_step = 0;
  std::uint8_t position_history = 0;   // 0, 1 or 2 positions known
  std::uint32_t ready_mismatches = 0;  // cycles with ServoRDY against the ready table
  std::uint32_t faulty = 0;            // cycles failing exactly one signature check
  std::array<std::uint32_t, kTxCheckCount> check_failures{};  // cycles failing each check
  std::uint8_t tables = 0;                                    // parameter tables shown active
  std::uint8_t last_table = 0;
  std::uint32_t table_changes = 0;
  CycleBits enabled;  // ServoEn
  CycleBits ack;      // ErrClearAck
  CycleBits zack;     // ZPulseAck
  // ServoEn set from the first cycle this window judged up to this cycle (exclusive): an enable
  // before the window switched it on (docs/layout.md#begins-in-a-fault).
  std::uint32_t enabled_from_start_until = 0;
  bool first_run_open = true;  // ServoEn has been set in every cycle judged so far
};

bool dead(std::uint32_t seen, std::uint32_t violations) {
  return violations > 2 + seen / kToleranceDivisor;
}

bool dead(const RxCandidate& c) {
  return dead(c.seen, c.violations);
}

// Not a TxPDO of this protocol: several checks failing at once in more than the tolerated
// cycles, or one check failing in most of them (a drive's fault fails one check now and then).
bool dead(const TxCandidate& c) {
  if (dead(c.seen, c.violations)) return true;
  return std::any_of(c.check_failures.begin(), c.check_failures.end(),
                     [&](std::uint32_t failures) { return failures > 2 + c.seen / 2; });
}

// A cyclic datagram: command, address and length identify it (docs/protocol.md §8).
struct Stream {
  std::uint8_t command = 0;
  std::uint32_t address = 0;
  std::uint16_t length = 0;
  std::uint32_t seen = 0;
  std::vector<RxCandidate> rx;  // by offset, when the master writes its data
  std::vector<TxCandidate> tx;  // by offset, when slaves write into it
  // The offsets of the candidates still alive, in order: a dead candidate is never observed
  // again, so it cannot come back, and most offsets die within the first cycles.
  std::vector<std::uint16_t> rx_alive;
  std::vector<std::uint16_t> tx_alive;
  // The master's copy of the current cycle, until its returned copy comes; a byte the returned
  // copy changed was written by a slave, so no RxPDO holds it (docs/protocol.md §8).
  std::vector<std::uint8_t> master_copy;
  bool master_pending = false;
  std::vector<std::uint8_t> slave_written;  // 1 by byte, when the master writes data too

  bool slaveWrote(std::size_t offset, std::size_t size) const {
    for (std::size_t i = offset; i < offset + size && i < slave_written.size(); ++i) {
      if (slave_written[i] != 0) return true;
    }
    return false;
  }

  bool logical() const { return ecat::isLogical(command); }
  std::uint16_t station() const { return static_cast<std::uint16_t>(address & 0xFFFF); }
  std::uint16_t ado() const { return static_cast<std::uint16_t>(address >> 16); }
  // Where offset `o` sits in process-image order: the logical image first, then each station.
  std::uint64_t imageAddress(std::size_t o) const {
    return logical() ? std::uint64_t{address} + o
                     : (std::uint64_t{1} << 40) | std::uint64_t{station()} << 16 | (ado() + o);
  }
  std::string describe() const {
    return logical() ? fmt::format("{} 0x{:08X}+{}", commandName(command), address, length)
                     : fmt::format("{} station 0x{:04X} 0x{:04X}+{}", commandName(command),
                                   station(), ado(), length);
  }
  static const char* commandName(std::uint8_t command) {
    switch (command) {
      case ecat::kLrd:
        return "LRD";
      case ecat::kLwr:
        return "LWR";
      case ecat::kLrw:
        return "LRW";
      case ecat::kFprd:
        return "FPRD";
      case ecat::kFpwr:
        return "FPWR";
      case ecat::kFprw:
        return "FPRW";
    }
    return "?";
  }
};

bool carriesProcessData(std::uint8_t command) {
  return ecat::isLogical(command) || command == ecat::kFprd || command == ecat::kFpwr ||
         command == ecat::kFprw;
}

struct ChosenTx {
  std::size_t stream;
  std::size_t offset;
  std::int64_t score;
  double confidence;
};

struct RxChoice {
  std::size_t stream;
  std::size_t offset;
};

}  // namespace

// The outputs-first hypothesis of §9.4 (an LRW of n × 50 bytes: n RxPDOs, then n TxPDOs), for a
// capture that holds no data the slaves wrote: each 10-byte slot of the outputs.
struct OutputsFirst {
  std::uint32_t address = 0;
  std::uint16_t length = 0;
  std::uint32_t seen = 0;
  std::vector<RxCandidate> slots;
};

struct LayoutInference::State {
  InferenceLimits limits;
  std::vector<Stream> streams;
  std::vector<OutputsFirst> outputs_first;
  bool master_seen = false;
  std::uint32_t cycles = 0;  // sightings of the first stream
  std::size_t bytes = 0;
  bool settled = false;

  Stream* streamFor(const Datagram& dg) {
    for (Stream& s : streams) {
      if (s.command == dg.command && s.address == dg.address && s.length == dg.length) return &s;
    }
    if (streams.size() >= limits.max_streams) return nullptr;
    Stream s;
    s.command = dg.command;
    s.address = dg.address;
    s.length = dg.length;
    if (ecat::writesSlaves(dg.command) && dg.length >= kRxPdoSize) {
      s.rx.resize(dg.length - kRxPdoSize + 1);
      s.slave_written.resize(dg.length, 0);
      bytes += 2 * std::size_t{dg.length};
    }
    if (ecat::readsSlaves(dg.command) && dg.length >= kTxPdoSize) {
      s.tx.resize(dg.length - kTxPdoSize + 1);
    }
    s.rx_alive.resize(s.rx.size());
    std::iota(s.rx_alive.begin(), s.rx_alive.end(), std::uint16_t{0});
    s.tx_alive.resize(s.tx.size());
    std::iota(s.tx_alive.begin(), s.tx_alive.end(), std::uint16_t{0});
    bytes += s.rx.size() * (sizeof(RxCandidate) + sizeof(std::uint16_t)) +
             s.tx.size() * (sizeof(TxCandidate) + sizeof(std::uint16_t));
    streams.push_back(std::move(s));
    return &streams.back();
  }

  void observeRx(RxCandidate& c, const std::uint8_t* pdo, std::uint32_t cycle) {
    ++c.seen;
    const std::uint32_t scw = le32(pdo + wordOffset(Word::Scw));
    if ((scw & kScwReserved) != 0) {
      ++c.violations;
      return;
    }
    if (scw != 0) ++c.active;
    const auto se = static_cast<std::uint8_t>(scw & kScwSe);
    const bool scw_changed = c.seen > 1 && scw != c.last_scw;
    if (scw_changed && c.scw_changed) ++c.scw_flaps;
    c.scw_changed = scw_changed;
    c.last_scw = scw;
    const auto ext_code = static_cast<std::uint16_t>(loadLe<2>(pdo + wordOffset(Word::ExtCode)));
    const bool ext_code_changed = c.seen > 1 && ext_code != c.last_ext_code;
    if (ext_code_changed && c.ext_code_changed) ++c.ext_code_flaps;
    c.ext_code_changed = ext_code_changed;
    c.last_ext_code = ext_code;
    noteTable(tableBit(Word::Scw, scw), c.tables, c.last_table, c.table_changes);
    if (se == kSeEnabled) c.enabled.set(cycle, bytes);
    if ((scw & kScwErrorClear) != 0) c.clear.set(cycle, bytes);
    if ((scw & kScwZPulseRequest) != 0) c.zpulse.set(cycle, bytes);
  }

  void observeTx(TxCandidate& c, const std::uint8_t* pdo, std::uint32_t cycle) {
    ++c.seen;
    const std::uint32_t ssw = le32(pdo + wordOffset(Word::Ssw));
    const std::uint32_t sew = le32(pdo + wordOffset(Word::Sew));
    const auto code = static_cast<std::int32_t>(le32(pdo + wordOffset(Word::MsgCode)));
    std::array<bool, kTxCheckCount> failed{};
    failed[kCheckSswReserved] = (ssw & kSswReserved) != 0;
    failed[kCheckSew] =
        (sew & kSewReserved) != 0 || ((sew & kSewCauses) != 0 && (sew & kSewSummary) == 0);
    failed[kCheckMessage] = code < 0 || code > kMaxMessageCode ||
                            !plausibleMessageData(code, le32(pdo + wordOffset(Word::MsgData)));
    for (Word w : {Word::MsgData, Word::ExtData1, Word::ExtData2, Word::ExtData3, Word::ExtData4}) {
      failed[kCheckFloats] = failed[kCheckFloats] || !plausibleFloat(le32(pdo + wordOffset(w)));
    }
    // The low 32 bits of ActPos are the position of either encoder kind (§1).
    const std::uint32_t position = le32(pdo + wordOffset(Word::ActPos));
    const std::int64_t step = static_cast<std::int32_t>(position - c.last_position);
    bool moved = false;
    if (c.position_history == 2) {
      const std::int64_t change = step - c.last_step;
      failed[kCheckPosition] = change > kMaxPositionStep || change < -kMaxPositionStep;
      moved = step != 0;
    }
    if (c.position_history < 2) ++c.position_history;
    c.last_position = position;
    c.last_step = step;
    // One check failing is a fault of a servo, which the rules report; several at once are data
    // of another kind (docs/layout.md).
    std::uint32_t failures = 0;
    for (std::size_t check = 0; check < kTxCheckCount; ++check) {
      if (!failed[check]) continue;
      ++failures;
      ++c.check_failures[check];
    }
    if (failures > 1) {
      ++c.violations;
      return;
    }
    if (failures == 1) ++c.faulty;
    if (moved) ++c.moves;
    if ((ssw & kSswStatus) != 0) ++c.status;
    if ((ssw & kSswServoEn) != 0) {
      c.enabled.set(cycle, bytes);
      if (c.first_run_open) c.enabled_from_start_until = cycle + 1;
    } else {
      c.first_run_open = false;
    }
    if ((ssw & kSswErrClearAck) != 0) c.ack.set(cycle, bytes);
    if ((ssw & kSswZPulseAck) != 0) c.zack.set(cycle, bytes);
    if (!readyPerTable(ssw, sew)) ++c.ready_mismatches;
    noteTable(tableBit(Word::Ssw, ssw), c.tables, c.last_table, c.table_changes);
  }

  // Slots cut short by the snap length are not observed.
  void observeOutputsFirst(const Datagram& dg, const ByteReader& frame) {
    constexpr std::size_t kAxisBytes = kRxPdoSize + kTxPdoSize;
    if (dg.command != ecat::kLrw || dg.length == 0 || dg.length % kAxisBytes != 0) return;
    OutputsFirst* entry = nullptr;
    for (OutputsFirst& o : outputs_first) {
      if (o.address == dg.address && o.length == dg.length) entry = &o;
    }
    if (entry == nullptr) {
      if (outputs_first.size() >= limits.max_streams) return;
      outputs_first.push_back(OutputsFirst{dg.address, dg.length, 0, {}});
      entry = &outputs_first.back();
      entry->slots.resize(dg.length / kAxisBytes);
      bytes += entry->slots.size() * sizeof(RxCandidate);
    }
    const std::uint32_t cycle = entry->seen++;
    for (std::size_t k = 0; k < entry->slots.size(); ++k) {
      const std::size_t at = dg.data_offset + k * kRxPdoSize;
      if (frame.has(at, kRxPdoSize)) observeRx(entry->slots[k], frame.data() + at, cycle);
    }
  }

  Stream* existingStream(const Datagram& dg) {
    for (Stream& s : streams) {
      if (s.command == dg.command && s.address == dg.address && s.length == dg.length) return &s;
    }
    return nullptr;
  }

  // A master's copy: kept until its returned copy shows which bytes the slaves wrote.
  void keepMasterCopy(const Datagram& dg, const ByteReader& frame) {
    if (!carriesProcessData(dg.command) || !dg.complete() || dg.length < kRxPdoSize) return;
    if (!frame.has(dg.data_offset, dg.length)) return;
    Stream* s = existingStream(dg);
    if (s == nullptr || s->slave_written.empty()) return;
    const std::uint8_t* data = frame.data() + dg.data_offset;
    s->master_copy.assign(data, data + dg.length);
    s->master_pending = true;
  }

  static void compareWithMaster(Stream& s, const std::uint8_t* data) {
    if (!s.master_pending) return;
    s.master_pending = false;
    // Bytes, not bits, so that the loop runs many bytes an instruction.
    for (std::size_t i = 0; i < s.master_copy.size(); ++i) {
      s.slave_written[i] |= static_cast<std::uint8_t>(s.master_copy[i] != data[i]);
    }
  }

  void observe(Stream& s, const std::uint8_t* data) {
    if (&s == &streams.front()) ++cycles;
    ++s.seen;
    const std::uint32_t cycle = cycles == 0 ? 0 : cycles - 1;
    observeAlive(s.rx, s.rx_alive,
                 [&](RxCandidate& c, std::size_t o) { observeRx(c, data + o, cycle); });
    observeAlive(s.tx, s.tx_alive,
                 [&](TxCandidate& c, std::size_t o) { observeTx(c, data + o, cycle); });
  }

  // Observes each candidate still alive, in offset order, and forgets those that died.
  template <class Candidate, class Observe>
  static void observeAlive(std::vector<Candidate>& all, std::vector<std::uint16_t>& alive,
                           Observe observe) {
    std::size_t kept = 0;
    for (std::size_t i = 0; i < alive.size(); ++i) {
      const std::uint16_t o = alive[i];
      observe(all[o], o);
      if (!dead(all[o])) alive[kept++] = o;
    }
    alive.resize(kept);
  }
};

LayoutInference::LayoutInference(InferenceLimits limits) : state_(std::make_unique<State>()) {
  state_->limits = limits;
}

LayoutInference::~LayoutInference() = default;

std::uint32_t LayoutInference::cycles() const {
  return state_->cycles;
}

bool LayoutInference::settled() const {
  return state_->settled;
}

void LayoutInference::onFrame(const EcatFrame& frame, const ByteReader& bytes, bool returned) {
  State& st = *state_;
  if (st.settled) return;
  if (frame.status != WalkStatus::Ok && frame.status != WalkStatus::Truncated) return;
  // The outputs as the master sent them (its copy, or the returned one where it has none).
  st.master_seen = st.master_seen || !returned;
  if (!returned || !st.master_seen) {
    for (std::size_t d = 0; d < frame.count; ++d) st.observeOutputsFirst(frame.datagrams[d], bytes);
  }
  if (!returned) {
    for (std::size_t d = 0; d < frame.count; ++d) st.keepMasterCopy(frame.datagrams[d], bytes);
    return;
  }
  const std::uint32_t cycles_before = st.cycles;
  for (std::size_t d = 0; d < frame.count; ++d) {
    const Datagram& dg = frame.datagrams[d];
    if (!carriesProcessData(dg.command) || !dg.complete() || dg.wkc == 0) continue;
    if (dg.length < kRxPdoSize || !bytes.has(dg.data_offset, dg.length)) continue;
    Stream* stream = st.streamFor(dg);
    if (stream == nullptr) continue;
    State::compareWithMaster(*stream, bytes.data() + dg.data_offset);
    st.observe(*stream, bytes.data() + dg.data_offset);
  }
  if (st.cycles == cycles_before) return;
  if (st.cycles >= st.limits.max_cycles || st.bytes >= st.limits.max_bytes) {
    st.settled = true;
    return;
  }
  // Early decision at doubling checkpoints: every servo-like TxPDO paired, every axis clear, each
  // by a handshake the window saw happen.
  const std::uint32_t c = st.cycles;
  if (c >= st.limits.min_cycles && (c & (c - 1)) == 0) {
    const InferenceResult result = decide();
    st.settled = !result.axes.empty() && result.refusal.empty() && result.unexplained == 0 &&
                 result.unconfirmed == 0;
  }
}

namespace {

// Best non-overlapping choice of `size`-byte regions of one stream by score (weighted interval
// scheduling); returns the chosen offsets.
std::vector<std::size_t> tile(const std::vector<std::int64_t>& score, std::size_t size) {
  const std::size_t n = score.size();
  std::vector<std::int64_t> best(n + size + 1, 0);
  for (std::size_t i = n; i-- > 0;) {
    best[i] = std::max(best[i + 1], score[i] > 0 ? score[i] + best[i + size] : 0);
  }
  std::vector<std::size_t> chosen;
  for (std::size_t i = 0; i < n;) {
    if (score[i] > 0 && score[i] + best[i + size] >= best[i + 1]) {
      chosen.push_back(i);
      i += size;
    } else {
      ++i;
    }
  }
  return chosen;
}

struct PairScore {
  std::int64_t score = std::numeric_limits<std::int64_t>::min();
  std::uint32_t agree = 0;
  // Of `agree`, the cycles after the ServoEn the window began with had ended: the others show only
  // that the word read 0x2 beside a drive already enabled, as a neighbour's steady input can.
  std::uint32_t agree_after_start = 0;
  std::uint32_t disagree = 0;
  std::uint32_t clear = 0;
  std::uint32_t zpulse = 0;
};

// SE 0x2 now or in the kDisableLag cycles before (the drive's disable delay), per cycle.
std::vector<std::uint64_t> recentlyEnabled(const CycleBits& se, std::uint32_t cycles) {
  const std::size_t words = (cycles + 63) / 64;
  std::vector<std::uint64_t> recent(words, 0);
  std::uint64_t carry = 0;
  for (std::size_t w = 0; w < words; ++w) {
    const std::uint64_t now = se.word(w);
    std::uint64_t r = now;
    for (std::uint32_t lag = 1; lag <= kDisableLag; ++lag)
      r |= (now << lag) | (carry >> (64 - lag));
    carry = now;
    recent[w] = r;
  }
  return recent;
}

// The first cycle with a bit set, or the largest cycle when none is.
std::uint32_t firstCycle(const CycleBits& bits) {
  for (std::size_t w = 0; w < bits.words.size(); ++w) {
    if (bits.words[w] != 0) {
      return static_cast<std::uint32_t>(64 * w + std::countr_zero(bits.words[w]));
    }
  }
  return std::numeric_limits<std::uint32_t>::max();
}

// The cycles of word `w` before cycle `end`.
std::uint64_t cyclesBefore(std::size_t w, std::uint32_t end) {
  const std::uint64_t first = 64 * std::uint64_t{w};
  if (end <= first) return 0;
  if (end >= first + 64) return ~std::uint64_t{0};
  return (std::uint64_t{1} << (end - first)) - 1;
}

// How well a candidate RxPDO's SE and ErrorClear explain a TxPDO's ServoEn and ErrClearAck.
// A ServoEn already set when the window began, until the SE first reads 0x2, is no evidence
// against the pair: an enable the window did not see switched it on, and whether the drive
// holds it too long is SE-003's to judge (docs/layout.md#begins-in-a-fault).
PairScore pairScore(const RxCandidate& rx, const std::vector<std::uint64_t>& recent,
                    const TxCandidate& tx) {
  PairScore p;
  const std::uint32_t unseen_enable_until =
      std::min(tx.enabled_from_start_until, firstCycle(rx.enabled));
  for (std::size_t w = 0; w < recent.size(); ++w) {
    const std::uint64_t en = tx.enabled.word(w);
    if (en == 0 && tx.ack.word(w) == 0 && tx.zack.word(w) == 0) continue;
    p.agree += popcount(rx.enabled.word(w) & en);
    p.agree_after_start +=
        popcount(rx.enabled.word(w) & en & ~cyclesBefore(w, tx.enabled_from_start_until));
    p.disagree += popcount(en & ~recent[w] & ~cyclesBefore(w, unseen_enable_until));
    p.clear += popcount(rx.clear.word(w) & tx.ack.word(w));
    p.zpulse += popcount(rx.zpulse.word(w) & tx.zack.word(w));
  }
  p.score = std::int64_t{p.agree} + p.clear + p.zpulse - kDisagreementWeight * p.disagree;
  return p;
}

// The evidence that a window is a servo's TxPDO, weighed over the whole learning window: ActPos
// moving and status bits set count for it; a cycle failing one signature check counts as no
// evidence, and each cycle against the structure (ServoRDY against the ready table, the SSW's
// parameter table changing on its own) outweighs several for it.
std::int64_t txScore(const TxCandidate& c) {
  if (c.seen < kMinObservations || dead(c)) return 0;
  const std::int64_t table_changes =
      c.table_changes > kRefusedTableChanges ? c.table_changes - kRefusedTableChanges : 0;
  const std::int64_t against = 2 * std::int64_t{c.faulty} +
                               kDisagreementWeight * c.ready_mismatches +
                               kTableChangeWeight * table_changes;
  return std::max<std::int64_t>(0, std::int64_t{c.moves} + c.status - against);
}

bool overlaps(std::size_t a, std::size_t a_size, std::size_t b, std::size_t b_size) {
  return a < b + b_size && b < a + a_size;
}

}  // namespace

// Without any data the slaves wrote, the outputs alone can still show the outputs-first layout:
// every slot of an LRW of n × 50 bytes holds a control word that keeps the reserved bits zero, and
// some axis is enabled (SE 0x2). A weaker decision than a paired one, and the evidence says so.
bool LayoutInference::outputsFirst(InferenceResult& result) const {
  const State& st = *state_;
  const OutputsFirst* best = nullptr;
  for (const OutputsFirst& o : st.outputs_first) {
    if (best == nullptr || o.seen > best->seen) best = &o;
  }
  if (best == nullptr || best->seen < kMinObservations) return false;
  bool enabled = false;
  for (const RxCandidate& slot : best->slots) {
    if (dead(slot.seen, slot.violations)) return false;
    enabled = enabled || slot.enabled.any();
  }
  if (!enabled) return false;
  const std::size_t n = best->slots.size();
  result.axes.clear();
  for (std::size_t k = 0; k < n; ++k) {
    InferredAxis axis;
    axis.config.name = fmt::format("axis{}", k);
    axis.config.outputs = static_cast<std::uint32_t>(best->address + k * kRxPdoSize);
    axis.config.inputs =
        static_cast<std::uint32_t>(best->address + n * kRxPdoSize + k * kTxPdoSize);
    axis.evidence.cycles = best->seen;
    axis.evidence.rx_violations = best->slots[k].violations;
    axis.evidence.confidence = 0.5;
    axis.evidence.outputs_only = true;
    result.axes.push_back(std::move(axis));
  }
  return true;
}

namespace {

// A control word whose SE may explain a ServoEn: written by the master, reserved bits zero, SE
// 0x2 at least once, and not changing cycle after cycle as a set point or a counter does: such a
// word passes 0x2 now and then and seems to explain a ServoEn nothing in the window switched on
// (docs/layout.md#begins-in-a-fault).
bool handshakeRx(const Stream& s, std::size_t o) {
  const RxCandidate& c = s.rx[o];
  return c.seen >= kMinObservations && !dead(c.seen, c.violations) && c.enabled.any() &&
         !dead(c.seen, c.scw_flaps) && !s.slaveWrote(o, kRxPdoSize);
}

// The handshake evidence of each TxPDO window that shows ServoEn: the best pair score of any
// control word that explains it (0 when none does). A neighbour of another protocol never has
// one, so a servo's TxPDO outweighs any window overlapping it (docs/layout.md).
std::vector<std::vector<std::int64_t>> handshakeScores(const std::vector<Stream>& streams,
                                                       std::uint32_t cycles) {
  struct Control {
    const Stream* stream;
    const RxCandidate* rx;
    std::vector<std::uint64_t> recent;
  };
  std::vector<Control> controls;
  for (const Stream& s : streams) {
    for (std::size_t o = 0; o < s.rx.size(); ++o) {
      if (handshakeRx(s, o))
        controls.push_back({&s, &s.rx[o], recentlyEnabled(s.rx[o].enabled, cycles)});
    }
  }
  std::vector<std::vector<std::int64_t>> scores(streams.size());
  for (std::size_t s = 0; s < streams.size(); ++s) {
    const Stream& ts = streams[s];
    scores[s].assign(ts.tx.size(), 0);
    if (controls.empty()) continue;
    for (std::size_t o = 0; o < ts.tx.size(); ++o) {
      const TxCandidate& t = ts.tx[o];
      if (!t.enabled.any() || t.seen < kMinObservations || dead(t)) continue;
      for (const Control& c : controls) {
        if (c.stream->logical() != ts.logical() ||
            (!ts.logical() && c.stream->station() != ts.station())) {
          continue;
        }
        const PairScore p = pairScore(*c.rx, c.recent, t);
        if (p.agree >= kMinAgreement && p.score > 0) scores[s][o] = std::max(scores[s][o], p.score);
      }
    }
  }
  return scores;
}

// 1. TxPDOs: the best tiling of each stream slaves write into, by the signature's evidence and
// the handshakes that explain it.
std::vector<ChosenTx> chooseTx(const std::vector<Stream>& streams, std::uint32_t cycles) {
  std::vector<ChosenTx> tx;
  const std::vector<std::vector<std::int64_t>> handshakes = handshakeScores(streams, cycles);
  for (std::size_t s = 0; s < streams.size(); ++s) {
    const Stream& stream = streams[s];
    std::vector<std::int64_t> score(stream.tx.size());
    for (std::size_t o = 0; o < stream.tx.size(); ++o) {
      score[o] = txScore(stream.tx[o]);
      if (score[o] > 0) score[o] += handshakes[s][o];
    }
    for (std::size_t o : tile(score, kTxPdoSize)) {
      std::int64_t rival = 0;  // the best overlapping candidate not chosen
      for (std::size_t r = o >= kTxPdoSize ? o - kTxPdoSize + 1 : 0;
           r < std::min(score.size(), o + kTxPdoSize); ++r) {
        if (r != o) rival = std::max(rival, score[r]);
      }
      const double confidence = 1.0 - static_cast<double>(rival) / static_cast<double>(score[o]);
      tx.push_back(ChosenTx{s, o, score[o], std::max(0.0, confidence)});
    }
  }
  std::sort(tx.begin(), tx.end(), [&](const ChosenTx& a, const ChosenTx& b) {
    return streams[a.stream].imageAddress(a.offset) < streams[b.stream].imageAddress(b.offset);
  });
  return tx;
}

// 2. RxPDOs: candidates in data the master writes, outside the chosen TxPDOs, whose SE was
// 0x2 at least once (no other can explain a ServoEn).
std::vector<RxChoice> chooseRx(const std::vector<Stream>& streams,
                               const std::vector<ChosenTx>& tx) {
  std::vector<RxChoice> rx;
  for (std::size_t s = 0; s < streams.size(); ++s) {
    const Stream& stream = streams[s];
    for (std::size_t o = 0; o < stream.rx.size(); ++o) {
      if (!handshakeRx(stream, o)) continue;
      const bool inside_tx = std::any_of(tx.begin(), tx.end(), [&](const ChosenTx& t) {
        return t.stream == s && overlaps(o, kRxPdoSize, t.offset, kTxPdoSize);
      });
      if (!inside_tx) rx.push_back(RxChoice{s, o});
    }
  }
  std::sort(rx.begin(), rx.end(), [&](const RxChoice& a, const RxChoice& b) {
    return streams[a.stream].imageAddress(a.offset) < streams[b.stream].imageAddress(b.offset);
  });
  return rx;
}

// The TxPDOs some RxPDO explains, each with its pair scores against every RxPDO candidate.
struct ServoCandidates {
  std::vector<ChosenTx> tx;
  std::vector<std::vector<PairScore>> pair;
  std::vector<std::string> unpaired;  // servo-like status words no control word explains
};

// 3. Pair scores; a TxPDO no RxPDO explains is not a servo's (or its axis never enabled).
ServoCandidates servoCandidates(const std::vector<Stream>& streams, std::uint32_t cycles,
                                const std::vector<ChosenTx>& tx, const std::vector<RxChoice>& rx,
                                InferenceResult& result) {
  ServoCandidates servos;
  std::vector<std::vector<std::uint64_t>> recent;
  recent.reserve(rx.size());
  for (const RxChoice& r : rx) {
    recent.push_back(recentlyEnabled(streams[r.stream].rx[r.offset].enabled, cycles));
  }
  std::vector<std::vector<PairScore>> pair(tx.size(), std::vector<PairScore>(rx.size()));
  for (std::size_t k = 0; k < tx.size(); ++k) {
    const Stream& ts = streams[tx[k].stream];
    const TxCandidate& t = ts.tx[tx[k].offset];
    bool any = false;
    for (std::size_t i = 0; i < rx.size(); ++i) {
      const Stream& rs = streams[rx[i].stream];
      if (rs.logical() != ts.logical() || (!ts.logical() && rs.station() != ts.station())) {
        continue;
      }
      pair[k][i] = pairScore(rs.rx[rx[i].offset], recent[i], t);
      any = any || (pair[k][i].agree >= kMinAgreement && pair[k][i].score > 0);
    }
    if (any) {
      servos.tx.push_back(tx[k]);
      servos.pair.push_back(std::move(pair[k]));
    } else if (t.status * 2 >= t.seen) {
      // A servo's status word that no control word explains yet: its axis may enable later.
      ++result.unexplained;
      if (t.enabled.any())
        servos.unpaired.push_back(fmt::format("{} offset {}", ts.describe(), tx[k].offset));
    }
  }
  return servos;
}

// 4. Pair RxPDO k with TxPDO k in process-image order, regions apart, best total.
// Each servo TxPDO's RxPDO index in `rx`, or rx.size() where none fits.
std::vector<std::size_t> assignPairs(const std::vector<Stream>& streams,
                                     const std::vector<RxChoice>& rx,
                                     const std::vector<std::vector<PairScore>>& servo_pair) {
  const std::size_t n = servo_pair.size();
  const std::size_t m = rx.size();
  constexpr std::int64_t kNone = std::numeric_limits<std::int64_t>::min() / 4;
  auto usable = [&](std::size_t k, std::size_t i) {
    return servo_pair[k][i].agree >= kMinAgreement && servo_pair[k][i].score > 0;
  };
  std::vector<std::vector<std::int64_t>> best(n, std::vector<std::int64_t>(m, kNone));
  std::vector<std::vector<std::size_t>> from(n, std::vector<std::size_t>(m, m));
  for (std::size_t k = 0; k < n; ++k) {
    std::int64_t prefix = kNone;  // best of row k-1 over candidates at least 10 bytes before i
    std::size_t prefix_at = m;
    std::size_t j = 0;
    for (std::size_t i = 0; i < m; ++i) {
      const std::uint64_t at = streams[rx[i].stream].imageAddress(rx[i].offset);
      while (k > 0 && j < m &&
             streams[rx[j].stream].imageAddress(rx[j].offset) + kRxPdoSize <= at) {
        if (best[k - 1][j] > prefix) {
          prefix = best[k - 1][j];
          prefix_at = j;
        }
        ++j;
      }
      if (!usable(k, i)) continue;
      if (k == 0) {
        best[k][i] = servo_pair[k][i].score;
      } else if (prefix > kNone) {
        best[k][i] = prefix + servo_pair[k][i].score;
        from[k][i] = prefix_at;
      }
    }
  }
  std::vector<std::size_t> choice(n, m);
  if (n > 0) {
    std::size_t at = m;
    for (std::size_t i = 0; i < m; ++i) {
      if (best[n - 1][i] > kNone && (at == m || best[n - 1][i] > best[n - 1][at])) at = i;
    }
    for (std::size_t k = n; k-- > 0 && at != m;) {
      choice[k] = at;
      at = from[k][at];
    }
  }
  return choice;
}

// The axis of rank k at these two windows, with the evidence they and their pairing gave; its
// confidence is the caller's.
InferredAxis axisAt(const std::vector<Stream>& streams, std::size_t k, const RxChoice& r,
                    const ChosenTx& chosen, const PairScore& p) {
  const Stream& rs = streams[r.stream];
  const Stream& ts = streams[chosen.stream];
  const TxCandidate& t = ts.tx[chosen.offset];
  InferredAxis axis;
  axis.config.name = fmt::format("axis{}", k);
  if (ts.logical()) {
    axis.config.outputs = static_cast<std::uint32_t>(rs.address + r.offset);
    axis.config.inputs = static_cast<std::uint32_t>(ts.address + chosen.offset);
  } else {
    axis.config.station = ts.station();
    axis.config.sm_outputs = static_cast<std::uint16_t>(rs.ado() + r.offset);
    axis.config.sm_inputs = static_cast<std::uint16_t>(ts.ado() + chosen.offset);
  }
  AxisEvidence& e = axis.evidence;
  e.cycles = t.seen;
  e.violations = t.violations + t.faulty;  // cycles failing any check
  e.rx_violations = rs.rx[r.offset].violations;
  e.actpos_moves = t.moves;
  e.status_cycles = t.status;
  e.ready_mismatches = t.ready_mismatches;
  e.enabled_agree = p.agree;
  e.enabled_disagree = p.disagree;
  e.clear_agree = p.clear;
  e.zpulse_agree = p.zpulse;
  e.handshakes_seen = p.agree + p.clear + p.zpulse;
  return axis;
}

// Whether a pair's handshakes include one the window saw happen: a ServoEn that SE 0x2 explains
// after the ServoEn the window began with, an ErrClearAck or a ZPulseAck. An agreement only over a
// ServoEn already set when the window began (or none at all) ends no window early.
bool seenInWindow(const PairScore& p) {
  return p.agree_after_start >= kMinAgreement || p.clear > 0 || p.zpulse > 0;
}

// Whether RxPDO window `i` could be axis k's instead of the chosen one: it overlaps the chosen
// window, or it lies between the RxPDOs chosen for the axes before and after k, so that the pairs
// stay in process-image order with it.
bool couldTakeSlot(const std::vector<Stream>& streams, const std::vector<RxChoice>& rx,
                   const std::vector<std::size_t>& choice, std::size_t k, std::size_t i) {
  const RxChoice& r = rx[choice[k]];
  if (i == choice[k]) return false;
  if (rx[i].stream == r.stream && overlaps(rx[i].offset, kRxPdoSize, r.offset, kRxPdoSize)) {
    return true;
  }
  auto at = [&](std::size_t j) { return streams[rx[j].stream].imageAddress(rx[j].offset); };
  return (k == 0 || at(choice[k - 1]) + kRxPdoSize <= at(i)) &&
         (k + 1 == choice.size() || at(i) + kRxPdoSize <= at(choice[k + 1]));
}

// 5. Confidence: how far the best rival is behind, for both PDOs; for the RxPDO, any window that
// could take its place (a word elsewhere that has agreed with the ServoEn as often, such as a
// neighbour's input that has not changed yet, makes the placement a guess: docs/layout.md).
// The axes go to `result`; the ones too close to a rival are returned, described.
std::vector<std::string> placeAxes(const std::vector<Stream>& streams,
                                   const std::vector<RxChoice>& rx, const ServoCandidates& servos,
                                   const std::vector<std::size_t>& choice,
                                   InferenceResult& result) {
  std::vector<std::string> ambiguous;
  const std::size_t n = servos.tx.size();
  const std::size_t m = rx.size();
  for (std::size_t k = 0; k < n; ++k) {
    const RxChoice& r = rx[choice[k]];
    const Stream& rs = streams[r.stream];
    const Stream& ts = streams[servos.tx[k].stream];
    const PairScore& p = servos.pair[k][choice[k]];
    std::int64_t rival = 0;
    for (std::size_t i = 0; i < m; ++i) {
      if (couldTakeSlot(streams, rx, choice, k, i)) {
        rival = std::max(rival, servos.pair[k][i].score);
      }
    }
    const double rx_confidence =
        std::max(0.0, 1.0 - static_cast<double>(rival) / static_cast<double>(p.score));
    InferredAxis axis = axisAt(streams, k, r, servos.tx[k], p);
    if (!seenInWindow(p)) ++result.unconfirmed;
    AxisEvidence& e = axis.evidence;
    e.confidence = std::min(servos.tx[k].confidence, rx_confidence);
    if (e.confidence < kMinConfidence) {
      ambiguous.push_back(fmt::format(
          "{} (RxPDO {} offset {}, TxPDO {} offset {}, confidence {:.0f} %)", axis.config.name,
          rs.describe(), r.offset, ts.describe(), servos.tx[k].offset, 100 * e.confidence));
    }
    result.axes.push_back(std::move(axis));
  }
  return ambiguous;
}

// The structure-only decision: each servo-like TxPDO of the chosen tiling gets the RxPDO of the
// same rank in process-image order, among the windows the structure allows; it decides only when
// exactly one such tiling exists.
struct StructureCandidates {
  std::vector<ChosenTx> tx;  // servo-like TxPDOs, in process-image order
  std::vector<RxChoice> rx;  // RxPDO windows the structure allows, in process-image order
  std::vector<std::vector<bool>> fits;  // [tx][rx]
};

bool servoLikeTx(const TxCandidate& t) {
  return t.seen >= kMinObservations && !dead(t) && t.status * 2 >= t.seen &&
         !dead(t.seen, t.ready_mismatches);
}

// A control word written by the master, reserved bits zero, steady (SE and every other bit) and
// mostly not all zero, beside a steady extra data code word.
bool servoLikeRx(const Stream& s, std::size_t o) {
  const RxCandidate& c = s.rx[o];
  return c.seen >= kMinObservations && !dead(c.seen, c.violations) && !dead(c.seen, c.scw_flaps) &&
         !dead(c.seen, c.ext_code_flaps) && c.active * 2 >= c.seen && !s.slaveWrote(o, kRxPdoSize);
}

// Whether RxPDO `rx` can be TxPDO `tx`'s: the same station (or both logical), every parameter
// table the SSW showed commanded by the SCW, and a ServoEn that SE explains.
bool structureFits(const Stream& rs, const RxCandidate& rx,
                   const std::vector<std::uint64_t>& recent, const Stream& ts,
                   const TxCandidate& tx) {
  if (rs.logical() != ts.logical() || (!ts.logical() && rs.station() != ts.station())) return false;
  // The SSW's table follows the SCW's: each table it showed was commanded, and it changed about as
  // often as the SCW's did (a drive may refuse a change now and then).
  if ((tx.tables & ~rx.tables) != 0) return false;
  if (rx.table_changes > tx.table_changes + kRefusedTableChanges) return false;
  if (!tx.enabled.any()) return true;
  if (!rx.enabled.any()) return false;
  const PairScore p = pairScore(rx, recent, tx);
  return p.agree >= kMinAgreement && p.score > 0;
}

StructureCandidates structureCandidates(const std::vector<Stream>& streams, std::uint32_t cycles,
                                        const std::vector<ChosenTx>& tiles) {
  StructureCandidates c;
  for (const ChosenTx& t : tiles) {
    if (servoLikeTx(streams[t.stream].tx[t.offset])) c.tx.push_back(t);
  }
  for (std::size_t s = 0; s < streams.size(); ++s) {
    const Stream& stream = streams[s];
    for (std::size_t o = 0; o < stream.rx.size(); ++o) {
      if (!servoLikeRx(stream, o)) continue;
      const bool inside_tx = std::any_of(c.tx.begin(), c.tx.end(), [&](const ChosenTx& t) {
        return t.stream == s && overlaps(o, kRxPdoSize, t.offset, kTxPdoSize);
      });
      if (!inside_tx) c.rx.push_back(RxChoice{s, o});
    }
  }
  std::sort(c.rx.begin(), c.rx.end(), [&](const RxChoice& a, const RxChoice& b) {
    return streams[a.stream].imageAddress(a.offset) < streams[b.stream].imageAddress(b.offset);
  });
  c.fits.assign(c.tx.size(), std::vector<bool>(c.rx.size(), false));
  for (std::size_t i = 0; i < c.rx.size(); ++i) {
    const Stream& rs = streams[c.rx[i].stream];
    const RxCandidate& rx = rs.rx[c.rx[i].offset];
    const std::vector<std::uint64_t> recent =
        rx.enabled.any() ? recentlyEnabled(rx.enabled, cycles) : std::vector<std::uint64_t>{};
    for (std::size_t k = 0; k < c.tx.size(); ++k) {
      const Stream& ts = streams[c.tx[k].stream];
      c.fits[k][i] = structureFits(rs, rx, recent, ts, ts.tx[c.tx[k].offset]);
    }
  }
  return c;
}

// For each rank k and RxPDO window i, in how many tilings (0, 1, or 2 for "more") RxPDO k is
// window i: the tilings of ranks before it times those after it.
std::vector<std::vector<std::uint32_t>> tilingsThrough(const std::vector<Stream>& streams,
                                                       const StructureCandidates& c) {
  const std::size_t n = c.tx.size();
  const std::size_t m = c.rx.size();
  auto at = [&](std::size_t i) { return streams[c.rx[i].stream].imageAddress(c.rx[i].offset); };
  auto capped = [](std::uint64_t v) {
    return static_cast<std::uint32_t>(std::min<std::uint64_t>(v, 2));
  };
  std::vector<std::vector<std::uint32_t>> before(n, std::vector<std::uint32_t>(m, 0));
  std::vector<std::vector<std::uint32_t>> after(n, std::vector<std::uint32_t>(m, 0));
  for (std::size_t k = 0; k < n; ++k) {
    std::uint64_t ways = 0;  // tilings of ranks 0..k-1 ending at least 10 bytes before i
    std::size_t j = 0;
    for (std::size_t i = 0; i < m; ++i) {
      while (k > 0 && j < m && at(j) + kRxPdoSize <= at(i))
        ways = capped(ways + before[k - 1][j++]);
      if (c.fits[k][i]) before[k][i] = k == 0 ? 1 : static_cast<std::uint32_t>(ways);
    }
  }
  for (std::size_t k = n; k-- > 0;) {
    std::uint64_t ways = 0;  // tilings of ranks k+1..n-1 starting at least 10 bytes after i
    std::size_t j = m;
    for (std::size_t i = m; i-- > 0;) {
      while (k + 1 < n && j > 0 && at(i) + kRxPdoSize <= at(j - 1))
        ways = capped(ways + after[k + 1][--j]);
      if (c.fits[k][i]) after[k][i] = k + 1 == n ? 1 : static_cast<std::uint32_t>(ways);
    }
  }
  for (std::size_t k = 0; k < n; ++k) {
    for (std::size_t i = 0; i < m; ++i) {
      before[k][i] = capped(std::uint64_t{before[k][i]} * after[k][i]);
    }
  }
  return before;
}

std::string describeRx(const std::vector<Stream>& streams, const RxChoice& r) {
  return fmt::format("{} offset {}", streams[r.stream].describe(), r.offset);
}

// The axis of rank k from the structure, its handshakes (if any) adding evidence; `unconfirmed`
// counts it when it has some but none the window saw happen.
InferredAxis structureAxis(const std::vector<Stream>& streams, std::uint32_t cycles,
                           const ChosenTx& chosen, const RxChoice& r, std::size_t k,
                           std::uint32_t& unconfirmed) {
  const Stream& rs = streams[r.stream];
  const Stream& ts = streams[chosen.stream];
  const PairScore p = pairScore(rs.rx[r.offset], recentlyEnabled(rs.rx[r.offset].enabled, cycles),
                                ts.tx[chosen.offset]);
  if (p.agree > 0 && !seenInWindow(p)) ++unconfirmed;
  InferredAxis axis = axisAt(streams, k, r, chosen, p);
  AxisEvidence& e = axis.evidence;
  e.paired_by_order = true;
  e.structure_only = e.handshakes_seen == 0;
  e.confidence = std::min(chosen.confidence, e.structure_only ? 0.5 : 0.75);
  return axis;
}

}  // namespace

// Decides from the structure alone when exactly one tiling fits; otherwise says why in `why`
// (empty when there was no servo-like TxPDO to place).
bool LayoutInference::fromStructure(InferenceResult& result, std::string& why) const {
  const State& st = *state_;
  const StructureCandidates c =
      structureCandidates(st.streams, st.cycles, chooseTx(st.streams, st.cycles));
  if (c.tx.empty()) return false;
  const std::vector<std::vector<std::uint32_t>> through = tilingsThrough(st.streams, c);
  std::vector<std::string> refused;
  std::vector<std::size_t> choice(c.tx.size(), c.rx.size());
  for (std::size_t k = 0; k < c.tx.size(); ++k) {
    std::vector<std::string> fits;
    for (std::size_t i = 0; i < c.rx.size(); ++i) {
      if (through[k][i] == 0) continue;
      fits.push_back(describeRx(st.streams, c.rx[i]));
      choice[k] = i;
    }
    const std::string tx =
        fmt::format("{} offset {}", st.streams[c.tx[k].stream].describe(), c.tx[k].offset);
    if (fits.empty()) {
      why = fmt::format(
          "from the structure, the status word at {} (rank {}) has no control word that fits "
          "(SCW reserved bits zero, SE steady, the SSW's parameter tables commanded, in "
          "process-image order)",
          tx, k);
      return false;
    }
    if (fits.size() > 1) {
      refused.push_back(
          fmt::format("the RxPDO of the status word at {} could be at {}: each passes "
                      "the structure checks, only one by right",
                      tx, fmt::join(fits, " or ")));
    } else if (c.tx[k].confidence < kMinConfidence) {
      refused.push_back(fmt::format(
          "the status word at {} passes the checks as well as an overlapping window", tx));
    }
  }
  if (!refused.empty()) {
    why = fmt::format("from the structure, {} slot{} refused: {}", refused.size(),
                      refused.size() == 1 ? "" : "s", fmt::join(refused, "; "));
    return false;
  }
  result.axes.clear();
  result.unconfirmed = 0;
  for (std::size_t k = 0; k < c.tx.size(); ++k) {
    result.axes.push_back(
        structureAxis(st.streams, st.cycles, c.tx[k], c.rx[choice[k]], k, result.unconfirmed));
  }
  return true;
}

namespace {

// Refused: say why, list the candidates, show how to write the configuration.
std::string refusal(const std::vector<Stream>& streams, std::uint32_t cycles,
                    const std::vector<std::string>& ambiguous,
                    const std::vector<std::string>& unpaired, std::size_t n,
                    const std::string& structure_why) {
  std::string why;
  if (!ambiguous.empty()) {
    why = fmt::format("the layout is ambiguous: more than one placement fits {}",
                      fmt::join(ambiguous, "; "));
  } else if (!unpaired.empty()) {
    why = fmt::format(
        "the layout is ambiguous: status words at {} look like a servo's but no control word "
        "explains their ServoEn",
        fmt::join(unpaired, ", "));
  } else if (n > 0) {
    why =
        "the layout is ambiguous: the control words cannot be paired with the status words in "
        "process-image order";
  } else if (streams.empty()) {
    why =
        "no cyclic process data was captured (no returned LRW, LRD, LWR, FPRD or FPWR of 10 "
        "bytes or more)";
  } else {
    why = fmt::format(
        "the layout is ambiguous or the evidence too weak: in {} cycles no status word's "
        "SSW.ServoEn followed a control word's SCW.SE (all axes idle, or the data all zeros or "
        "constant)",
        cycles);
  }
  if (!structure_why.empty()) why = fmt::format("{}; {}", why, structure_why);
  std::vector<std::string> listed;
  for (const Stream& s : streams) listed.push_back(s.describe());
  return fmt::format(
      "{}; cyclic datagrams: {}; give the layout in a --config file, one [[axis]] per servo with "
      "the logical addresses of its 10-byte RxPDO and 40-byte TxPDO",
      why, listed.empty() ? std::string("none") : fmt::format("{}", fmt::join(listed, ", ")));
}

}  // namespace

InferenceResult LayoutInference::decide() const {
  const State& st = *state_;
  InferenceResult result;
  result.cycles = st.cycles;
  const std::vector<ChosenTx> tx = chooseTx(st.streams, st.cycles);
  const std::vector<RxChoice> rx = chooseRx(st.streams, tx);
  const ServoCandidates servos = servoCandidates(st.streams, st.cycles, tx, rx, result);
  const std::vector<std::size_t> choice = assignPairs(st.streams, rx, servos.pair);
  const std::size_t n = servos.tx.size();
  const std::size_t m = rx.size();
  const bool assigned =
      n > 0 && std::all_of(choice.begin(), choice.end(), [m](std::size_t c) { return c != m; });
  std::vector<std::string> ambiguous;
  if (assigned) ambiguous = placeAxes(st.streams, rx, servos, choice, result);
  const bool paired = assigned && ambiguous.empty() && servos.unpaired.empty();
  if (paired && result.unexplained == 0) return result;
  // Status words no handshake explains (idle axes): the structure may place every axis.
  InferenceResult structure = result;
  std::string structure_why;
  if (fromStructure(structure, structure_why)) return structure;
  if (paired) return result;
  if (st.streams.empty() && outputsFirst(result)) return result;
  result.candidates = std::move(result.axes);
  result.axes.clear();
  result.refusal = refusal(st.streams, st.cycles, ambiguous, servos.unpaired, n, structure_why);
  return result;
}

std::string describeInference(const AxisEvidence& e) {
  std::string how;
  if (e.outputs_only) {
    how = "from the outputs only (no data the slaves wrote was captured)";
  } else if (e.structure_only) {
    how = "found from the structure only, no handshake seen";
  } else {
    how = fmt::format("{} handshake cycles", e.handshakes_seen);
  }
  if (e.paired_by_order) how += "; RxPDO paired with the TxPDO of the same rank in image order";
  return fmt::format("inferred: {}; confidence {:.0f} %", how, 100 * e.confidence);
}

std::string describeEvidence(const InferredAxis& axis) {
  const AxisEvidence& e = axis.evidence;
  auto mark = [](bool ok) { return ok ? "ok" : "weak"; };
  if (e.outputs_only) {
    return fmt::format(
        "cycles {}; outputs only (no data the slaves wrote was captured): the outputs-first "
        "layout's RxPDO slot, SCW reserved bits zero ({} mismatches), an axis enabled; the "
        "TxPDO's place follows from the layout, unchecked; confidence {:.0f} %",
        e.cycles, e.rx_violations, 100 * e.confidence);
  }
  std::string text = fmt::format(
      "cycles {}; signature (reserved bits zero, SEW summary, message code 0..{}, finite floats, "
      "smooth ActPos) {} ({} TxPDO and {} RxPDO mismatches); ActPos moved in {} cycles; SSW "
      "status bits in {} cycles; SSW.ServoEn followed SCW.SE in {} cycles, against it in {} ({}); "
      "ErrClearAck with ErrorClear in {} cycles",
      e.cycles, kMaxMessageCode, mark(e.violations == 0 && e.rx_violations == 0), e.violations,
      e.rx_violations, e.actpos_moves, e.status_cycles, e.enabled_agree, e.enabled_disagree,
      mark(e.enabled_agree >= kMinAgreement && e.enabled_disagree == 0), e.clear_agree);
  if (e.zpulse_agree > 0) {
    text += fmt::format("; ZPulseAck with ZPulseRequest in {} cycles", e.zpulse_agree);
  }
  if (e.paired_by_order) {
    text += fmt::format(
        "; ServoRDY against the ready table in {} cycles; the SSW's parameter tables commanded "
        "by the SCW; RxPDO paired with the TxPDO of the same rank in process-image order",
        e.ready_mismatches);
  }
  if (e.structure_only) text += "; found from the structure only, no handshake seen";
  return text + fmt::format("; confidence {:.0f} %", 100 * e.confidence);
}

}  // namespace ncservo
