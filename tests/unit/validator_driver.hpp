// Test helper: drives a Validator with default-layout cycles (docs/protocol.md §9.4) built byte by
// byte — per cycle a master copy (outputs, WKC 0) and a returned copy (outputs and inputs, WKC
// 3n) at exact integer-nanosecond timestamps — and names every frame by its cycle and copy, so
// that tests state where a finding must be reported as "the master copy of cycle 31".
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "default_layout.hpp"
#include "frame_builder.hpp"
#include "ncservo/incidents/incident_detector.hpp"
#include "ncservo/rules/finding.hpp"
#include "ncservo/rules/rules.hpp"
#include "ncservo/rules/validator.hpp"

namespace ncservo::test {

inline constexpr std::int64_t kMs = 1'000'000;
inline constexpr std::int64_t kUs = 1'000;
inline constexpr std::int64_t kCycleNs = kMs;  // a 1 ms cycle
// Capture time of cycle 0's master copy: a realistic epoch time, so that no arithmetic on
// timestamps gets away with small numbers.
inline constexpr std::int64_t kEpochNs = 1'700'000'000'000'000'000;
inline constexpr std::int64_t kEnd = 1'000'000;  // "to the end of the script"
inline constexpr std::uint32_t kLrwAddress = 0x00010000;

// SCW 0x406: SE 0x2, EMGON 1, Brake 1. SSW 0x83: ServoEn, ServoRDY, PulseEnabled (absolute).
inline constexpr std::uint32_t kScwRunning = 0x406;
inline constexpr std::uint32_t kSswRunning = 0x83;

// SCW values (docs/protocol.md §2). EMGON and Brake are 1 unless a name says otherwise.
inline constexpr std::uint32_t kScwOff = 0x404;    // SE 0x0
inline constexpr std::uint32_t kScwArmed = 0x405;  // SE 0x1
inline constexpr std::uint32_t kScwSe3 = 0x407;    // SE 0x3
inline constexpr std::uint32_t kZRequest = 0x800;  // ZPulseRequest
inline constexpr std::uint32_t kClear = 0x200;     // ErrorClear
// SSW values (§3).
inline constexpr std::uint32_t kSswReady = 0x02;  // ServoRDY only: disabled, ready
inline constexpr std::uint32_t kSswNone = 0x00;
inline constexpr std::uint32_t kIncremental = 0x04;
inline constexpr std::uint32_t kZAck = 0x08;
inline constexpr std::uint32_t kClearAck = 0x10;
inline constexpr std::uint32_t kNoEncoder = 0x400;
// SEW values (§4).
inline constexpr std::uint32_t kSummary = 0x1;
inline constexpr std::uint32_t kEncoderErr = 0x2;
inline constexpr std::uint32_t kEcatTErr = 0x8000;

struct AxisCycle {
  std::uint32_t scw = kScwRunning;
  std::uint32_t ssw = kSswRunning;
  std::uint32_t sew = 0;
  std::int32_t msg = 0;
  std::optional<std::int32_t> ssp;  // 100 + the axis's index when none
  float msg_data = 0;
};

enum class Copy : std::uint8_t { Master, Returned };

// A frame of a script, named by cycle and copy.
struct At {
  Copy copy;
  std::int64_t cycle;
};
inline At M(std::int64_t cycle) {
  return At{Copy::Master, cycle};
}
inline At R(std::int64_t cycle) {
  return At{Copy::Returned, cycle};
}

// What a script sends: per cycle and axis the PDO words, per cycle which copies are captured,
// the returned copy's WKC and the timestamps. Later settings override earlier ones.
class Script {
 public:
  explicit Script(std::int64_t cycles = 60) : cycles_(cycles) {}

  Script& axes(std::size_t n) {
    axes_ = n;
    return *this;
  }
  // The returned copy's delay after the master's copy.
  Script& delay(std::int64_t ns) {
    delay_ns_ = ns;
    return *this;
  }
  Script& base(std::uint32_t scw, std::uint32_t ssw, std::uint32_t sew = 0) {
    base_ = AxisCycle{scw, ssw, sew, 0, std::nullopt, 0};
    return *this;
  }
  // Cycles [from, to) of one axis.
  Script& scw(std::int64_t from, std::int64_t to, std::uint32_t v, std::size_t axis = 0) {
    return span(from, to, Field::Scw, v, axis);
  }
  Script& ssw(std::int64_t from, std::int64_t to, std::uint32_t v, std::size_t axis = 0) {
    return span(from, to, Field::Ssw, v, axis);
  }
  Script& sew(std::int64_t from, std::int64_t to, std::uint32_t v, std::size_t axis = 0) {
    return span(from, to, Field::Sew, v, axis);
  }
  Script& msg(std::int64_t from, std::int64_t to, std::int32_t v, std::size_t axis = 0) {
    return span(from, to, Field::Msg, static_cast<std::uint32_t>(v), axis);
  }
  // Cycles [from, to): the message data, and the set point.
  Script& msgData(std::int64_t from, std::int64_t to, float v, std::size_t axis = 0) {
    std::uint32_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    return span(from, to, Field::MsgData, bits, axis);
  }
  Script& ssp(std::int64_t from, std::int64_t to, std::int32_t v, std::size_t axis = 0) {
    return span(from, to, Field::Ssp, static_cast<std::uint32_t>(v), axis);
  }
  // Cycles [from, to): the returned copy's WKC.
  Script& wkc(std::int64_t from, std::int64_t to, std::uint16_t v) {
    return span(from, to, Field::Wkc, v, 0);
  }
  Script& noMaster(std::int64_t from, std::int64_t to) {
    return span(from, to, Field::NoMaster, 1, 0);
  }
  Script& noReturned(std::int64_t from, std::int64_t to) {
    return span(from, to, Field::NoReturned, 1, 0);
  }
  // Neither copy of cycles [from, to) is in the capture.
  Script& missing(std::int64_t from, std::int64_t to) {
    return noMaster(from, to).noReturned(from, to);
  }
  // An explicit timestamp for one frame.
  Script& time(At at, std::int64_t ns) {
    times_.push_back({at, ns});
    return *this;
  }
  // Frames of cycle `from` on are timed `ns` later (earlier when negative): a capture
  // discontinuity (docs/timing.md#rule-time).
  Script& shift(std::int64_t from, std::int64_t ns) {
    shift_from_ = from;
    shift_ns_ = ns;
    return *this;
  }
  // Every cycle's datagram has the same index (by default it counts the cycles).
  Script& constantIndex() {
    constant_index_ = true;
    return *this;
  }
  Script& settings(RuleSettings s) {
    settings_ = std::move(s);
    return *this;
  }
  // Axis k's slave has the station address `first` + k, which the layout names; then every
  // cycle's frame also writes each drive's mailbox areas (SM0, SM1) and reads its SM1
  // (docs/drive-messages.md), with WKC 1 in the returned copy where the drive answers.
  Script& stations(std::uint16_t first) {
    first_station_ = first;
    return *this;
  }
  // The returned copy of `cycle` reads a CoE emergency from the axis's drive.
  Script& emergency(std::int64_t cycle, std::uint16_t code, std::size_t axis = 0) {
    return message(cycle, axis, coe(1, emcy(code, 0x01, Bytes(5, 0))));
  }
  // The returned copy of `cycle` reads the answer to an upload of 1003h:01 (expedited, 4 bytes).
  Script& historyRead(std::int64_t cycle, std::uint32_t value, std::size_t axis = 0) {
    return message(cycle, axis, coe(3, sdo(0x43, 0x1003, 1, value)));
  }
  std::optional<std::uint16_t> firstStation() const { return first_station_; }
  // The mailbox the axis's drive answers with in `cycle`'s returned copy, if any.
  const Bytes* mailboxOf(std::int64_t cycle, std::size_t axis) const {
    for (const Message& m : messages_) {
      if (m.cycle == cycle && m.axis == axis) return &m.mailbox;
    }
    return nullptr;
  }

  std::int64_t cycles() const { return cycles_; }
  std::uint8_t indexOf(std::int64_t cycle) const {
    return constant_index_ ? 0x80 : static_cast<std::uint8_t>(cycle & 0xFF);
  }
  std::size_t axisCount() const { return axes_; }
  const RuleSettings& ruleSettings() const { return settings_; }

  AxisCycle valuesOf(std::int64_t cycle, std::size_t axis) const {
    AxisCycle v = base_;
    for (const Span& s : spans_) {
      if (s.axis != axis || cycle < s.from || cycle >= s.to) continue;
      switch (s.field) {
        case Field::Scw:
          v.scw = s.value;
          break;
        case Field::Ssw:
          v.ssw = s.value;
          break;
        case Field::Sew:
          v.sew = s.value;
          break;
        case Field::Msg:
          v.msg = static_cast<std::int32_t>(s.value);
          break;
        case Field::MsgData:
          std::memcpy(&v.msg_data, &s.value, sizeof v.msg_data);
          break;
        case Field::Ssp:
          v.ssp = static_cast<std::int32_t>(s.value);
          break;
        default:
          break;
      }
    }
    return v;
  }
  std::uint16_t wkcOf(std::int64_t cycle) const {
    auto wkc = static_cast<std::uint16_t>(3 * axes_);
    for (const Span& s : spans_) {
      if (s.field == Field::Wkc && cycle >= s.from && cycle < s.to) {
        wkc = static_cast<std::uint16_t>(s.value);
      }
    }
    return wkc;
  }
  bool captured(At at) const {
    const Field field = at.copy == Copy::Master ? Field::NoMaster : Field::NoReturned;
    for (const Span& s : spans_) {
      if (s.field == field && at.cycle >= s.from && at.cycle < s.to) return false;
    }
    return true;
  }
  std::int64_t timeOf(At at) const {
    for (const auto& [where, ns] : times_) {
      if (where.copy == at.copy && where.cycle == at.cycle) return ns;
    }
    return kEpochNs + at.cycle * kCycleNs + (at.copy == Copy::Returned ? delay_ns_ : 0) +
           (at.cycle >= shift_from_ ? shift_ns_ : 0);
  }

 private:
  enum class Field : std::uint8_t { Scw, Ssw, Sew, Msg, MsgData, Ssp, Wkc, NoMaster, NoReturned };
  struct Span {
    std::int64_t from, to;
    Field field;
    std::uint32_t value;
    std::size_t axis;
  };
  Script& span(std::int64_t from, std::int64_t to, Field field, std::uint32_t value,
               std::size_t axis) {
    spans_.push_back(Span{from, to, field, value, axis});
    return *this;
  }

  struct Message {
    std::int64_t cycle;
    std::size_t axis;
    Bytes mailbox;
  };
  Script& message(std::int64_t cycle, std::size_t axis, const Bytes& body) {
    std::uint8_t counter = 1;  // 1..7, each message of a drive the next (a repeat has the same)
    for (const Message& m : messages_) counter = m.axis == axis ? counter % 7 + 1 : counter;
    messages_.push_back(Message{cycle, axis, mbx(3, counter, body)});
    return *this;
  }

  std::int64_t cycles_;
  std::optional<std::uint16_t> first_station_;
  std::vector<Message> messages_;
  std::size_t axes_ = 1;
  std::int64_t delay_ns_ = 0;
  std::int64_t shift_from_ = kEnd;
  std::int64_t shift_ns_ = 0;
  bool constant_index_ = false;
  AxisCycle base_;
  std::vector<Span> spans_;
  std::vector<std::pair<At, std::int64_t>> times_;
  RuleSettings settings_;
};

// The default layout's cyclic LRW of all axes: n RxPDOs then n TxPDOs. `index` is the datagram
// index; a master that numbers its frames (as SOEM does) makes consecutive cycles' datagram lists
// differ, so that a master copy never looks like the returned copy of the one before (§8).
// Its data: n RxPDOs then n TxPDOs (inputs zero in the master's copy).
inline Bytes lrwData(const std::vector<AxisCycle>& axes, bool returned) {
  Bytes data;
  for (std::size_t k = 0; k < axes.size(); ++k) {
    const Bytes rx = rxPdo(axes[k].ssp.value_or(static_cast<std::int32_t>(100 + k)), axes[k].scw);
    data.insert(data.end(), rx.begin(), rx.end());
  }
  for (const AxisCycle& a : axes) {
    const Bytes tx = returned ? txPdo(TxValues(0, a.ssw, a.sew, a.msg, a.msg_data)) : Bytes(40, 0);
    data.insert(data.end(), tx.begin(), tx.end());
  }
  return data;
}
// The frame.
inline Bytes cyclicFrame(const std::vector<AxisCycle>& axes, bool returned, std::uint16_t wkc,
                         std::uint8_t index = 0x80) {
  FrameBuilder builder;
  builder.add(Dg{ecat::kLrw, index, kLrwAddress, lrwData(axes, returned),
                 returned ? wkc : std::uint16_t{0}});
  return builder.bytes();
}

// The drives' mailbox areas in a script with stations (Script::stations).
inline constexpr std::uint16_t kMailboxOut = 0x1000;
inline constexpr std::uint16_t kMailboxIn = 0x1080;

// A script's frame at `at`: its cycle's LRW and, with stations, per axis the write of its
// drive's SM0 and SM1 (mailbox mode) and the read of its SM1.
inline Bytes scriptFrame(const Script& script, At at) {
  std::vector<AxisCycle> values;
  for (std::size_t a = 0; a < script.axisCount(); ++a)
    values.push_back(script.valuesOf(at.cycle, a));
  const bool returned = at.copy == Copy::Returned;
  if (!script.firstStation()) {
    return cyclicFrame(values, returned, script.wkcOf(at.cycle), script.indexOf(at.cycle));
  }
  FrameBuilder builder;
  builder.add(Dg{ecat::kLrw, script.indexOf(at.cycle), kLrwAddress, lrwData(values, returned),
                 returned ? script.wkcOf(at.cycle) : std::uint16_t{0}});
  for (std::size_t a = 0; a < script.axisCount(); ++a) {
    const auto station = static_cast<std::uint16_t>(*script.firstStation() + a);
    const Bytes sms =
        concat({smBlock(kMailboxOut, kMailboxArea, 0x26), smBlock(kMailboxIn, kMailboxArea, 0x22)});
    builder.add(Dg{ecat::kFpwr, 0, physical(station, ecat::kRegSyncManager0), sms,
                   static_cast<std::uint16_t>(returned ? 1 : 0)});
    const Bytes* mailbox = returned ? script.mailboxOf(at.cycle, a) : nullptr;
    builder.add(Dg{ecat::kFprd, 0, physical(station, kMailboxIn),
                   mailbox != nullptr ? *mailbox : Bytes(kMailboxArea, 0),
                   static_cast<std::uint16_t>(mailbox != nullptr ? 1 : 0)});
  }
  return builder.bytes();
}

// A station-addressed axis (docs/protocol.md §8): an FPWR of its outputs and an FPRD of its
// inputs each cycle, the AL status polled by FPRD.
inline constexpr std::uint16_t kStation = 0x03E9;
inline constexpr std::uint16_t kSmOutputs = 0x1100;
inline constexpr std::uint16_t kSmInputs = 0x1180;

inline DecoderOptions stationAxis() {
  AxisConfig axis;
  axis.name = "X";
  axis.station = kStation;
  axis.sm_outputs = kSmOutputs;
  axis.sm_inputs = kSmInputs;
  DecoderOptions options;
  options.axes = {axis};
  return options;
}

// An AL status read (0x0130) of the station, with the AL status code (0x0134) when `code` is
// given: a master's poll reads the 6 bytes in one FPRD.
inline Dg alStatusRead(std::uint16_t al, std::optional<std::uint16_t> code, bool returned,
                       std::uint8_t index) {
  Bytes status;
  putLe(status, returned ? al : 0, 2);
  if (code) {
    putLe(status, 0, 2);
    putLe(status, returned ? *code : 0, 2);
  }
  return Dg{ecat::kFprd, index, physical(kStation, ecat::kRegAlStatus), std::move(status),
            static_cast<std::uint16_t>(returned ? 1 : 0)};
}

// One cycle of the station-addressed axis and, when `al` is given, an FPRD of its AL status
// (and code); the returned copy has WKC 1 everywhere.
inline Bytes stationFrame(std::uint32_t scw, std::uint32_t ssw, std::optional<std::uint16_t> al,
                          bool returned, std::uint32_t sew = 0,
                          std::optional<std::uint16_t> code = std::nullopt) {
  const std::uint16_t wkc = returned ? 1 : 0;
  FrameBuilder builder;
  builder.add(Dg{ecat::kFpwr, 1, physical(kStation, kSmOutputs), rxPdo(100, scw), wkc});
  builder.add(Dg{ecat::kFprd, 2, physical(kStation, kSmInputs),
                 returned ? txPdo(TxValues(0, ssw, sew)) : Bytes(40, 0), wkc});
  if (al) builder.add(alStatusRead(*al, code, returned, 3));
  return builder.bytes();
}

// The AL status read alone, in a frame of its own.
inline Bytes alStatusFrame(std::uint16_t al, bool returned,
                           std::optional<std::uint16_t> code = std::nullopt) {
  FrameBuilder builder;
  builder.add(alStatusRead(al, code, returned, 7));
  return builder.bytes();
}

// Feeds frames to one Validator, numbering them from 1, and keeps every finding.
class ValidatorDriver {
 public:
  // Without explicit axes, the layout is the outputs-first one of the first frame (what the
  // inference decides for these frames, default_layout.hpp).
  explicit ValidatorDriver(RuleSettings settings = RuleSettings{},
                           DecoderOptions options = DecoderOptions{})
      : settings_(std::move(settings)), options_(std::move(options)) {}

  // One captured frame at `time_ns`; returns the findings reported on it.
  const std::vector<Finding>& feed(const Bytes& bytes, std::int64_t time_ns) {
    const Walked w = walk(bytes);
    if (!validator_) {
      if (options_.axes.empty() && options_.default_layout) {
        options_ = defaultLayoutOf(*w.frame, options_);
      }
      validator_.emplace(options_, settings_);
      incidents_.emplace(settings_);
    }
    const Observation& view = validator_->onFrame(++frame_, time_ns, *w.frame, w.reader());
    incidents_->onFrame(*validator_, view, frame_, time_ns);
    all_.insert(all_.end(), validator_->findings().begin(), validator_->findings().end());
    return validator_->findings();
  }

  // Every frame of a script, in capture order; records where each cycle's copies went.
  void run(const Script& script) {
    for (std::int64_t k = 0; k < script.cycles(); ++k) {
      std::vector<AxisCycle> values;
      for (std::size_t a = 0; a < script.axisCount(); ++a) values.push_back(script.valuesOf(k, a));
      for (Copy copy : {Copy::Master, Copy::Returned}) {
        const At at{copy, k};
        if (!script.captured(at)) continue;
        feed(cyclicFrame(values, copy == Copy::Returned, script.wkcOf(k), script.indexOf(k)),
             script.timeOf(at));
        frames_.push_back({at, frame_});
      }
    }
    finish();
  }

  // The capture ends; returns the findings reported on its last frame then.
  const std::vector<Finding>& finish() {
    validator_->finish();
    incidents_->finish();
    all_.insert(all_.end(), validator_->findings().begin(), validator_->findings().end());
    return validator_->findings();
  }

  // The frame number a script gave a cycle's copy (0 if it was not captured).
  std::uint64_t frameOf(At at) const {
    for (const auto& [where, number] : frames_) {
      if (where.copy == at.copy && where.cycle == at.cycle) return number;
    }
    return 0;
  }

  const std::vector<Finding>& findings() const { return all_; }
  const Validator& validator() const { return *validator_; }
  // The incidents found beside the validator (docs/incidents.md).
  const IncidentDetector& incidents() const { return *incidents_; }
  std::uint64_t frames() const { return frame_; }

 private:
  RuleSettings settings_;
  DecoderOptions options_;
  std::optional<Validator> validator_;
  std::optional<IncidentDetector> incidents_;
  std::uint64_t frame_ = 0;
  std::vector<Finding> all_;
  std::vector<std::pair<At, std::uint64_t>> frames_;
};

// "SE-001 axis 0 at 11 since 11", "COM-002 bus at 40 since 37": comparable and readable.
inline std::string describe(RuleId rule, std::optional<std::uint16_t> axis, std::uint64_t at,
                            std::uint64_t since) {
  return std::string(ruleDef(rule).code) +
         (axis ? " axis " + std::to_string(*axis) : std::string(" bus")) + " at " +
         std::to_string(at) + " since " + std::to_string(since);
}
inline std::string describe(const Finding& f) {
  return describe(f.rule, f.axis, f.at.frame, f.since.frame);
}

}  // namespace ncservo::test
