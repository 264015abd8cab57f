// Finds the incidents of one capture frame by frame, after the validator judged each frame
// (docs/incidents.md). Memory is bounded: per axis, rolling windows of the minute before for the
// motor temperature and of the 100 ms before for everything else, and at most kMaxIncidents.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <tuple>
#include <vector>

#include "ncservo/incidents/incident.hpp"
#include "ncservo/rules/rules.hpp"
#include "ncservo/rules/validator.hpp"

namespace ncservo {

struct AxisTrack;
struct BusTrack;
struct LinkMark;

class IncidentDetector {
 public:
  static constexpr std::size_t kMaxIncidents = 1000;

  explicit IncidentDetector(const RuleSettings& settings);
  ~IncidentDetector();
  IncidentDetector(const IncidentDetector&) = delete;
  IncidentDetector& operator=(const IncidentDetector&) = delete;

  // One frame the validator has just judged (its findings, accounting and AL changes are the
  // frame's, and its models measured the frame's values); `time_ns` is its capture time.
  void onFrame(const Validator& validator, const Observation& observation, std::uint64_t frame,
               std::int64_t time_ns);
  // The capture ended: the incidents not recovered end on its last frame.
  void finish();

  // In the order they began (frame order). A cause is final when the incident is added, but
  // for one whose axis lost cycles before it in a capture whose master reads the ESCs' error
  // counters: a read up to kLinkReadWaitNs later can still make it link-fault
  // (docs/incidents.md#link-fault).
  const std::vector<Incident>& incidents() const { return incidents_; }
  // Whether incident `index`'s cause is final. Its evidence can still take the drive's own
  // words read later (docs/incidents.md#the-drives-own-words).
  bool causeFinal(std::size_t index) const;
  // The incidents whose cause (to link-fault) or evidence the last frame changed, by index.
  const std::vector<std::size_t>& revised() const { return revised_; }
  // Incidents beyond kMaxIncidents, counted only.
  std::uint64_t omitted() const { return omitted_; }

 private:
  AxisTrack& track(std::uint16_t axis);
  void add(Incident incident, const AxisTrack* axis, const AxisMeasurements* signals,
           const MessageHistory* messages, std::uint32_t sew, const AlCodeMark* al_code = nullptr);
  void takeAlCodes(const Validator& validator, const Mark& at);
  void takeLinks(const Validator& validator, const Mark& at);
  // The incident just added waits for a link read, if its axis lost cycles before it.
  void awaitLink(const AxisTrack* axis);
  void reviseToLink(std::size_t index, const LinkMark& link);
  void markRevised(std::size_t index);  // once per frame
  void takeDriveWords(const Validator& validator, const Mark& at);
  // The incident just added: the drive's words of the 100 ms before, and those to come.
  void addDriveWords(Incident& incident, const AxisTrack& axis, const Mark& at) const;
  void awaitDriveWords(std::uint16_t axis);
  // The last AL status code read of the axis's slave, if the axis has a station and one was.
  const AlCodeMark* alCodeOfAxis(const Validator& validator, std::uint16_t axis) const;
  void takeFaults(const Validator& validator, const Observation& observation);
  void checkOutage(const Validator& validator);
  void takeAlChanges(const Validator& validator);
  void resetWindows();

  std::uint32_t failure_limit_;  // telegram_failure_limit (COM-005)
  Stamp last_;                   // the last frame given
  std::int64_t clock_ns_ = 0;    // its time on the segment's clock
  bool outage_ = false;          // every axis failing: a bus outage is open
  Mark outage_at_;               // ... since this frame
  std::size_t open_faults_ = 0;  // drive faults not yet recovered
  std::vector<std::unique_ptr<AxisTrack>> axes_;
  // By station address, else 0x10000 + ring position: the slaves the AL tracker knows, so
  // bounded as its directory is.
  std::map<std::uint32_t, AlCodeMark> al_codes_;
  // Incidents whose cause a later read of the links' counters can still make link-fault.
  struct AwaitedLink {
    std::size_t incident;
    std::uint64_t first_failed;  // the first frame of the failures before it
    std::int64_t until_ns;       // on the segment's clock
  };
  static constexpr std::size_t kMaxAwaited = 64;
  bool counters_read_ = false;  // the capture has shown a read of a slave's error counters
  std::vector<AwaitedLink> awaited_;
  std::vector<std::size_t> revised_;  // this frame's
  // Incidents whose evidence takes the drive's words read up to kLinkReadWaitNs after them.
  struct AwaitedWords {
    std::size_t incident;
    std::uint16_t axis;
    std::int64_t until_ns;
    std::size_t taken = 0;  // at most kMaxDriveWords
  };
  static constexpr std::size_t kMaxDriveWords = 4;
  std::vector<AwaitedWords> awaited_words_;
  std::unique_ptr<BusTrack> bus_;
  std::vector<Incident> incidents_;
  std::uint64_t omitted_ = 0;
  std::uint64_t segments_ = 0;
  // The incidents so far in this segment by kind, axis (or station) and cause: their ordinals.
  using OrdinalKey =
      std::tuple<IncidentKind, std::optional<std::uint16_t>, std::optional<std::uint16_t>, CauseId>;
  std::map<OrdinalKey, std::uint32_t> ordinals_;
};

}  // namespace ncservo
