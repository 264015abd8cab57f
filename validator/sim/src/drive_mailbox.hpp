// What the simulated drives say through their mailbox, and the NC's reads of it
// (docs/simulate.md#diagnosis, docs/protocol.md §11): each drive's CoE side sends an emergency
// for each SEW cause bit that rises and an error reset when ServoErrors falls, keeps its error
// history (1003h) and answers SDO requests for its diagnosis objects; the NC reads 1001h, 1003h:00
// and 1003h:01 after each fault it sees, one request at a time.
#pragma once

#include <cstdint>
#include <deque>
#include <optional>
#include <vector>

#include "ncservo/model/mailbox_tracker.hpp"
#include "ncservo/sim/diagnosis_truth.hpp"
#include "ncservo/sim/faults.hpp"
#include "segment.hpp"

namespace ncservo::sim {

class DriveMailbox {
 public:
  void quirk(MailboxQuirk quirk);
  // Once per cycle, after the drive stepped: its SEW now, the requests the master wrote into
  // the slave's SM0 (answered into its SM1), the emergencies for what rose or fell.
  void step(std::uint32_t sew, Esc& esc);

 private:
  void send(Esc& esc, std::uint8_t service, const std::uint8_t* body, std::size_t size,
            DriveSaid said);
  void emergency(Esc& esc, std::uint16_t code, std::uint8_t error_register, std::uint8_t number);
  void answer(Esc& esc, const std::vector<std::uint8_t>& request);
  // An SDO message of the drive's: an answer's value, or an abort's code, in `data`.
  void sdo(Esc& esc, std::uint8_t service, std::uint8_t command, DriveMessage::Kind kind,
           std::uint16_t index, std::uint8_t subindex, std::uint32_t data);
  void upload(Esc& esc, std::uint16_t index, std::uint8_t subindex, std::uint32_t value,
              std::size_t size);
  void abort(Esc& esc, std::uint16_t index, std::uint8_t subindex, std::uint32_t code);

  std::deque<std::uint32_t> history_;  // 1003h, newest first
  std::uint8_t error_register_ = 0;    // 1001h
  std::uint16_t last_code_ = 0;        // 603Fh
  std::uint32_t sew_ = 0;
  std::uint8_t counter_ = 0;
  std::vector<MailboxQuirk> pending_;  // emergencies of a quirk, sent at the next step
  bool silent_next_ = false;
  bool wrong_code_next_ = false;
};

// The NC's side: the reads it makes after a fault, and any other it is told to make.
class NcMailbox {
 public:
  void upload(std::uint16_t index, std::uint8_t subindex);
  void faultSeen();  // 1001h:00, 1003h:00, 1003h:01
  // The request to write into SM0 now: one waits and none is open.
  std::optional<std::vector<std::uint8_t>> takeRequest();
  // What the master read from SM1: an SDO answer or abort closes the open request.
  void answered(const std::vector<std::uint8_t>& message);

 private:
  struct Request {
    std::uint16_t index;
    std::uint8_t subindex;
  };
  std::deque<Request> queue_;
  bool open_ = false;
  std::uint8_t counter_ = 0;
};

}  // namespace ncservo::sim
