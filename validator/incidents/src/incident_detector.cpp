#include "ncservo/incidents/incident_detector.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "incident_tracks.hpp"
#include "ncservo/incidents/causes.hpp"
#include "ncservo/model/al_tracker.hpp"
#include "ncservo/model/mailbox_tracker.hpp"
#include "ncservo/protocol/fields.hpp"
#include "ncservo/protocol/pdo.hpp"
#include "ncservo/protocol/word_bits.hpp"
#include "ncservo/wire/diagnosis_texts.hpp"
#include "ncservo/wire/ecat_wire.hpp"

namespace ncservo {

namespace {

// A slave by its station address, else by its ring position.
std::uint32_t alCodeKey(const SlaveRef& slave) {
  return slave.station ? *slave.station : 0x10000u + slave.position.value_or(0xFFFF);
}

constexpr std::int64_t kEvidenceWindowNs = 100 * kMsNs;
constexpr std::size_t kMaxFindingEvidence = 8;

const FieldDef* sewField(const SewCause& cause) {
  for (const FieldDef& f : kFields) {
    if (f.word == Word::Sew && f.view == FieldView::Cause && f.mask == cause.mask) return &f;
  }
  return nullptr;
}

const AxisMeasurements* measurementsOf(const AxisModel* model) {
  return model != nullptr ? &model->measurements() : nullptr;
}

const MessageHistory* messagesOf(const AxisModel* model) {
  return model != nullptr ? &model->measurements().messages() : nullptr;
}

}  // namespace

const char* incidentKindName(IncidentKind kind) {
  switch (kind) {
    case IncidentKind::DriveFault:
      return "drive-fault";
    case IncidentKind::BusOutage:
      return "bus-outage";
    case IncidentKind::Esm:
      return "esm";
  }
  return "?";
}

std::string sewBitName(const SewCause& cause) {
  const FieldDef* f = sewField(cause);
  if (f == nullptr) return cause.display;
  constexpr std::string_view kPrefix = "ncservo.sew.";
  return std::string(std::string_view(f->filter).substr(kPrefix.size()));
}

const char* sewBitLabel(const SewCause& cause) {
  const FieldDef* f = sewField(cause);
  return f != nullptr ? f->label : cause.display;
}

std::string incidentHeadline(const Incident& incident, const std::string& axis_name) {
  switch (incident.kind) {
    case IncidentKind::DriveFault: {
      std::string codes;
      for (const SewCause* cause : incident.errors) {
        codes += fmt::format("{}{}", codes.empty() ? " " : "+", cause->display);
      }
      return fmt::format("{} fault{}", axis_name, codes);
    }
    case IncidentKind::BusOutage:
      return "bus outage";
    case IncidentKind::Esm: {
      std::string who = incident.axis ? axis_name
                        : incident.station
                            ? fmt::format("station 0x{:04X}", *incident.station)
                            : fmt::format("ring position {}", incident.position.value_or(0));
      return fmt::format("{} ESM {}", who, incident.what);
    }
  }
  return "?";
}

IncidentDetector::IncidentDetector(const RuleSettings& settings)
    : failure_limit_(settings.telegram_failure_limit), bus_(std::make_unique<BusTrack>()) {}

IncidentDetector::~IncidentDetector() = default;

AxisTrack& IncidentDetector::track(std::uint16_t axis) {
  if (axis >= axes_.size()) axes_.resize(axis + 1u);
  if (!axes_[axis]) axes_[axis] = std::make_unique<AxisTrack>();
  return *axes_[axis];
}

void IncidentDetector::resetWindows() {
  for (auto& a : axes_) {
    if (a) a->resetWindows();
  }
  bus_->findings.clear();
  bus_->links.clear();
  al_codes_.clear();
  awaited_.clear();  // their causes are final: the windows start afresh
  awaited_words_.clear();
}

bool IncidentDetector::causeFinal(std::size_t index) const {
  return std::none_of(awaited_.begin(), awaited_.end(),
                      [&](const AwaitedLink& a) { return a.incident == index; });
}

void IncidentDetector::awaitLink(const AxisTrack* axis) {
  // A master that has not read the counters of a single slave so far is not polling them.
  if (!counters_read_ || axis == nullptr || incidents_.empty()) return;
  const Incident& incident = incidents_.back();
  if (incident.cause == CauseId::LinkFault) return;
  const Mark at{incident.at.frame, clock_ns_, incident.at.time_ns};
  const std::uint64_t first = firstFailedFrame(*axis, at, kShortWindowNs);
  if (first == 0) return;
  if (awaited_.size() >= kMaxAwaited) awaited_.erase(awaited_.begin());  // the oldest is final
  awaited_.push_back(AwaitedLink{incidents_.size() - 1, first, clock_ns_ + kLinkReadWaitNs});
}

// This frame's rises of the links' counters: kept for the cause rows, and each makes the
// incidents waiting for it link-fault.
void IncidentDetector::takeLinks(const Validator& validator, const Mark& at) {
  counters_read_ = validator.escErrors().reads() > 0;
  if (!awaited_.empty()) {
    std::erase_if(awaited_, [&](const AwaitedLink& a) { return a.until_ns < at.clock_ns; });
  }
  for (const LinkErrorEvent& event : validator.escErrors().frameLinkEvents()) {
    if (event.link.frame != at.frame) break;  // an earlier frame's: this one read no counters
    bus_->links.push(LinkMark{at, event});
    const LinkMark& link = bus_->links.newest();
    std::erase_if(awaited_, [&](const AwaitedLink& a) {
      if (!link.covers(a.first_failed)) return false;
      reviseToLink(a.incident, link);
      return true;
    });
  }
}

namespace {

// What of a drive's mailbox tells about its fault: its emergencies, and the answers to reads of
// the objects its diagnosis uses (diag::kObjects), but 1003h's number of entries.
bool driveWord(const DriveMessage& m) {
  if (m.kind == DriveMessage::Kind::Emergency) return true;
  if (m.kind != DriveMessage::Kind::SdoUpload || diag::objectName(m.index) == nullptr) return false;
  return m.index != diag::kPredefinedErrorField || m.subindex > 0;
}

}  // namespace

void IncidentDetector::takeDriveWords(const Validator& validator, const Mark& at) {
  if (!awaited_words_.empty()) {
    std::erase_if(awaited_words_, [&](const AwaitedWords& a) {
      return a.until_ns < at.clock_ns || a.taken >= kMaxDriveWords;
    });
  }
  for (const DriveMessage& m : validator.mailbox().frameMessages()) {
    if (m.frame != at.frame) break;  // an earlier frame's: this one read no mailbox
    if (!driveWord(m) || !m.slave.station) continue;
    const std::optional<std::uint16_t> axis = validator.decoder().axisOfStation(*m.slave.station);
    if (!axis) continue;
    AxisTrack& a = track(*axis);
    a.words.push(DriveWordMark{at, "drive: " + describeDriveMessage(m)});
    for (AwaitedWords& awaited : awaited_words_) {
      if (awaited.axis != *axis || awaited.taken >= kMaxDriveWords) continue;
      incidents_[awaited.incident].evidence.push_back(
          IncidentEvidence{at.stamp(), a.words.newest().what});
      ++awaited.taken;
      markRevised(awaited.incident);
    }
  }
}

void IncidentDetector::addDriveWords(Incident& incident, const AxisTrack& axis,
                                     const Mark& at) const {
  for (std::size_t i = axis.words.size(); i-- > 0;) {  // oldest first
    const DriveWordMark& word = axis.words[i];
    if (within(word.at, at, kShortWindowNs)) {
      incident.evidence.push_back(IncidentEvidence{word.at.stamp(), word.what});
    }
  }
}

void IncidentDetector::awaitDriveWords(std::uint16_t axis) {
  if (incidents_.empty()) return;
  if (awaited_words_.size() >= kMaxAwaited) awaited_words_.erase(awaited_words_.begin());
  awaited_words_.push_back(
      AwaitedWords{incidents_.size() - 1, axis, clock_ns_ + kLinkReadWaitNs, 0});
}

void IncidentDetector::reviseToLink(std::size_t index, const LinkMark& link) {
  Incident& incident = incidents_[index];
  const std::optional<std::uint16_t> station = incident.axis ? std::nullopt : incident.station;
  std::uint32_t& old_count = ordinals_[{incident.kind, incident.axis, station, incident.cause}];
  if (old_count == incident.ordinal) --old_count;  // the last of its cause: no gap left
  incident.cause = CauseId::LinkFault;
  incident.cause_text = fmt::format("{}; {}", linkRiseText(link), incident.cause_text);
  incident.evidence.push_back(linkRiseEvidence(link));
  incident.ordinal = ++ordinals_[{incident.kind, incident.axis, station, incident.cause}];
  markRevised(index);
}

void IncidentDetector::markRevised(std::size_t index) {
  if (std::find(revised_.begin(), revised_.end(), index) == revised_.end()) {
    revised_.push_back(index);
  }
}

void IncidentDetector::takeAlCodes(const Validator& validator, const Mark& at) {
  for (const AlCodeRead& read : validator.al().codeReads()) {
    al_codes_[alCodeKey(read.slave)] = AlCodeMark{read.code, at};
  }
}

const AlCodeMark* IncidentDetector::alCodeOfAxis(const Validator& validator,
                                                 std::uint16_t axis) const {
  if (al_codes_.empty()) return nullptr;
  for (const AxisInfo& info : validator.decoder().axes()) {
    if (info.index != axis || !info.has_station) continue;
    const auto found = al_codes_.find(alCodeKey(SlaveRef{info.station, std::nullopt}));
    return found != al_codes_.end() ? &found->second : nullptr;
  }
  return nullptr;
}

// The incident's cause from the first matching row, its evidence (the row's and the findings of
// the 100 ms before), and what the drive reported before it: `signals` are the axis's model's
// measurements (null where it has none), `messages` what the drive had said before.
void IncidentDetector::add(Incident incident, const AxisTrack* axis,
                           const AxisMeasurements* signals, const MessageHistory* messages,
                           std::uint32_t sew, const AlCodeMark* al_code) {
  if (incidents_.size() >= kMaxIncidents) {
    ++omitted_;
    return;
  }
  const Mark at{incident.at.frame, clock_ns_, incident.at.time_ns};
  CauseContext context{incident.kind, axis, signals,       messages, bus_.get(),
                       sew,           at,   incident.what, {}};
  if (al_code != nullptr) context.al_code = *al_code;
  CauseMatch match;
  for (const CauseDef& row : kCauses) {
    match = CauseMatch{};
    if (row.test(context, match)) {
      incident.cause = row.id;
      break;
    }
  }
  incident.cause_text = std::move(match.text);
  incident.evidence = std::move(match.evidence);
  if (axis != nullptr && incident.axis) addDriveWords(incident, *axis, at);
  std::vector<const FindingMark*> findings;
  const Ring<FindingMark, 16>* rings[] = {axis != nullptr ? &axis->findings : nullptr,
                                          &bus_->findings};
  for (const Ring<FindingMark, 16>* ring : rings) {
    if (ring == nullptr) continue;
    for (std::size_t i = 0; i < ring->size(); ++i) {
      if (within((*ring)[i].at, at, kEvidenceWindowNs)) findings.push_back(&(*ring)[i]);
    }
  }
  std::sort(findings.begin(), findings.end(),
            [](const FindingMark* a, const FindingMark* b) { return a->at.frame > b->at.frame; });
  if (findings.size() > kMaxFindingEvidence) findings.resize(kMaxFindingEvidence);
  for (const FindingMark* f : findings) {
    const bool known = std::any_of(
        incident.evidence.begin(), incident.evidence.end(),
        [&](const IncidentEvidence& e) { return e.at.frame == f->at.frame && e.what == f->what; });
    if (!known) incident.evidence.push_back(IncidentEvidence{f->at.stamp(), f->what});
  }
  std::stable_sort(
      incident.evidence.begin(), incident.evidence.end(),
      [](const IncidentEvidence& a, const IncidentEvidence& b) { return a.at.frame < b.at.frame; });
  if (messages != nullptr) {
    incident.before = messages->before;
    for (std::size_t k = 0; k < kBefore.size(); ++k) {
      incident.before_at[k] = messages->before_at[k].stamp();
    }
  }
  incident.end = incident.at;
  const std::optional<std::uint16_t> station = incident.axis ? std::nullopt : incident.station;
  incident.ordinal = ++ordinals_[{incident.kind, incident.axis, station, incident.cause}];
  incidents_.push_back(std::move(incident));
}

void IncidentDetector::onFrame(const Validator& validator, const Observation& observation,
                               std::uint64_t frame, std::int64_t time_ns) {
  // docs/timing.md#rule-time: the windows are measured on the segment's clock, and a new
  // segment starts them afresh.
  if (validator.segments().count() != segments_) {
    if (segments_ != 0) resetWindows();
    segments_ = validator.segments().count();
    ordinals_.clear();
  }
  clock_ns_ = validator.segments().now();
  last_ = Stamp{frame, time_ns};
  const Mark at{frame, clock_ns_, time_ns};

  for (const AxisAccount& account : validator.frameAccounts()) {
    if (account.outcome == AxisAccount::Outcome::Good) continue;
    AxisTrack& a = track(account.axis);
    const bool lost = account.outcome == AxisAccount::Outcome::Lost;
    if (a.failures.size() == 0 ||
        a.failures.newest().last.clock_ns + kFailureMergeNs < at.clock_ns) {
      a.failures.push(FailureRun{at, at, account.first, account.last, account.between, 0, 0});
    }
    FailureRun& run = a.failures.newest();
    run.last = at;
    run.last_frame = account.last;
    run.between = run.between && account.between;
    (lost ? run.lost : run.failed) += account.cycles;
  }
  for (const Finding& f : validator.findings()) {
    const RuleDef& rule = ruleDef(f.rule);
    FindingMark mark{at, f.rule, fmt::format("{} {}", rule.code, f.message)};
    if (f.axis) {
      track(*f.axis).findings.push(std::move(mark));
    } else {
      bus_->findings.push(std::move(mark));
    }
  }
  if (!revised_.empty()) revised_.clear();
  // What slaves said comes only in frames with register commands; a wait for it still expires.
  if (observation.decode.registers || !awaited_.empty() || !awaited_words_.empty()) {
    takeAlCodes(validator, at);
    takeLinks(validator, at);
    takeDriveWords(validator, at);
  }
  takeFaults(validator, observation);
  checkOutage(validator);
  takeAlChanges(validator);
}

// Each placed axis's inputs of this frame, as its model measured them: a drive fault begins where
// SEW.ServoErrors rises, and recovers when the errors cleared and the drive was enabled again.
void IncidentDetector::takeFaults(const Validator& validator, const Observation& observation) {
  using namespace bits;
  if (observation.servo_error_rises == 0 && open_faults_ == 0) return;
  const FrameDecode& decode = observation.decode;
  // The placements are in axis order: the tracks grow once, then each is one index away.
  if (decode.axis_count > 0) track(decode.axes[decode.axis_count - 1].axis);
  for (std::size_t i = 0; i < decode.axis_count; ++i) {
    const std::uint16_t index = decode.axes[i].axis;
    std::unique_ptr<AxisTrack>& held = axes_[index];
    if (!held) held = std::make_unique<AxisTrack>();
    AxisTrack& a = *held;
    if (!observation.values[i].has_tx) continue;
    const AxisMeasurements& signals = validator.axis(index)->measurements();
    const std::uint32_t ssw = signals.ssw();
    const std::uint32_t sew = signals.sew();
    if (signals.sewRoseIn(last_.frame) & kServoErrors) {
      if (a.open) {
        incidents_[*a.open].end = last_;  // a new fault before the last one recovered
        incidents_[*a.open].ended = true;
        a.open.reset();
        --open_faults_;
      }
      Incident incident;
      incident.kind = IncidentKind::DriveFault;
      incident.axis = index;
      incident.at = last_;
      for (const SewCause& cause : kSewCauses) {
        if (sew & cause.mask) incident.errors.push_back(&cause);
      }
      std::sort(incident.errors.begin(), incident.errors.end(),
                [](const SewCause* x, const SewCause* y) { return x->mask < y->mask; });
      add(std::move(incident), &a, &signals, &signals.messagesBefore(last_.frame), sew,
          alCodeOfAxis(validator, index));
      if (!incidents_.empty() && incidents_.back().at.frame == last_.frame &&
          incidents_.back().axis == index) {  // added: not past kMaxIncidents
        a.open = incidents_.size() - 1;
        ++open_faults_;
        awaitLink(&a);
        awaitDriveWords(index);
      }
    }
    // docs/incidents.md#recovery: the errors cleared (ServoErrors fell), then enabled again.
    if (a.open) {
      Incident& open = incidents_[*a.open];
      if (!open.error_clear && (sew & kServoErrors) == 0) open.error_clear = last_;
      if (open.error_clear && (ssw & kServoEn) != 0 && (sew & kServoErrors) == 0) {
        open.reenabled = last_;
        open.end = last_;
        open.recovered = open.ended = true;
        a.open.reset();
        --open_faults_;
      }
    }
  }
}

// docs/incidents.md#bus-outage: every axis seen so far failing for more than
// telegram_failure_limit consecutive cycles; it ends where one axis's cycle runs again.
void IncidentDetector::checkOutage(const Validator& validator) {
  if (!outage_ && validator.frameAccounts().empty()) return;
  bool every = true;
  bool any_ok = false;
  std::size_t axes = 0;
  const AxisTrack* worst = nullptr;
  const AxisModel* worst_model = nullptr;
  std::uint64_t worst_lost = 0;
  for (std::size_t i = 0; i < validator.axisCount(); ++i) {
    const AxisModel* model = validator.axis(i);
    if (model == nullptr) continue;
    ++axes;
    every = every && model->consecutiveFailed() > failure_limit_;
    any_ok = any_ok || model->consecutiveFailed() == 0;
    if (i < axes_.size() && axes_[i] && axes_[i]->failures.size() > 0) {
      const FailureRun& run = axes_[i]->failures[0];
      if (worst == nullptr || run.lost + run.failed > worst_lost) {
        worst = axes_[i].get();
        worst_model = model;
        worst_lost = run.lost + run.failed;
      }
    }
  }
  if (outage_) {
    if (!any_ok) return;
    outage_ = false;
    for (auto it = incidents_.rbegin(); it != incidents_.rend(); ++it) {
      if (it->kind != IncidentKind::BusOutage) continue;
      it->end = last_;
      it->reenabled = last_;
      it->recovered = it->ended = true;
      // Declared once the limit was passed; told whole now that it is over, as its axes' drive
      // faults tell it.
      const Mark now{last_.frame, clock_ns_, last_.time_ns};
      const std::string whole =
          worst == nullptr
              ? std::string()
              : lostCyclesText(*worst, now, now.clock_ns - outage_at_.clock_ns + kFailureMergeNs,
                               nullptr);
      if (it->cause == CauseId::CommunicationLoss && !whole.empty()) {
        it->cause_text = "every axis failing: " + whole;
      }
      break;
    }
    return;
  }
  if (axes == 0 || !every) return;
  outage_ = true;
  outage_at_ = Mark{last_.frame, clock_ns_, last_.time_ns};
  Incident incident;
  incident.kind = IncidentKind::BusOutage;
  incident.at = last_;
  add(std::move(incident), worst, measurementsOf(worst_model), messagesOf(worst_model), 0);
  if (!incidents_.empty() && incidents_.back().kind == IncidentKind::BusOutage &&
      incidents_.back().at.frame == last_.frame) {
    awaitLink(worst);
  }
}

// docs/incidents.md#esm: a slave's AL state read falling from OP that the master did not request
// (its last AL control request was OP, or none was seen); back in OP ends it.
void IncidentDetector::takeAlChanges(const Validator& validator) {
  for (const AlOpChange& change : validator.al().opChanges()) {
    const std::optional<std::uint16_t> axis =
        change.slave.station ? validator.decoder().axisOfStation(*change.slave.station)
                             : std::nullopt;
    if (change.to == ecat::kAlOp) {
      for (auto it = incidents_.rbegin(); it != incidents_.rend(); ++it) {
        if (it->kind != IncidentKind::Esm || it->ended || it->station != change.slave.station ||
            it->position != change.slave.position) {
          continue;
        }
        it->end = last_;
        it->reenabled = last_;
        it->recovered = it->ended = true;
        break;
      }
      continue;
    }
    // A state the master asked for (a shutdown, a restart) is no incident.
    if (change.requested && *change.requested != ecat::kAlOp) continue;
    Incident incident;
    incident.kind = IncidentKind::Esm;
    incident.axis = axis;
    incident.station = change.slave.station;
    incident.position = change.slave.position;
    incident.at = last_;
    incident.what =
        fmt::format("{} \u2192 {} (AL status 0x{:04X}{})", alStateName(change.from),
                    alStateName(change.to), change.raw,
                    change.status_code ? fmt::format(", status code 0x{:04X}", *change.status_code)
                                       : std::string());
    const AxisModel* model = axis ? validator.axis(*axis) : nullptr;
    const auto code = al_codes_.find(alCodeKey(change.slave));
    add(std::move(incident), axis ? &track(*axis) : nullptr, measurementsOf(model),
        messagesOf(model), 0, code != al_codes_.end() ? &code->second : nullptr);
  }
}

void IncidentDetector::finish() {
  awaited_.clear();  // no read comes any more: every cause is final
  awaited_words_.clear();
  for (Incident& incident : incidents_) {
    if (!incident.ended) incident.end = last_;
  }
}

}  // namespace ncservo
