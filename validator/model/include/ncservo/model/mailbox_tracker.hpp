// What the drives said over their mailboxes (PROTOCOL.md §11, docs/drive-messages.md): each
// slave's mailbox areas, found from the start-up's SM0/SM1 writes or, where no start-up was
// captured, from what is seen in use (a write whose data starts with a mailbox header, then a
// read of the same slave whose data does); the CoE emergencies and SDO answers read from them,
// each answer paired with its request; EoE, FoE, SoE, AoE and VoE counted, not decoded.
//
// Bounded: per slave at most kMaxPending open requests and one segmented transfer, of which only
// the byte count and the first 8 bytes are kept; a transfer that runs past its size (or
// kMaxTransferBytes) or whose toggle bit is out of order is dropped with a note. The messages
// listed stop at kMaxMessages (then counted), the notes at kMaxNotes.
#pragma once

#include <array>
#include <bitset>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "ncservo/base/byte_reader.hpp"
#include "ncservo/layout/axis_config.hpp"
#include "ncservo/model/bus_events.hpp"
#include "ncservo/wire/diagnosis_texts.hpp"
#include "ncservo/wire/ethercat.hpp"
#include "ncservo/wire/mailbox.hpp"
#include "ncservo/wire/slave_directory.hpp"

namespace ncservo {

// One thing a drive said (JSON `drive_messages`, INTERFACES.md).
struct DriveMessage {
  enum class Kind : std::uint8_t { Emergency, SdoUpload, SdoDownload, SdoAbort };
  Kind kind = Kind::Emergency;
  std::uint64_t frame = 0;  // the frame that carried it (an SDO's response)
  std::int64_t time_ns = 0;
  std::optional<std::uint64_t> request_frame;  // an SDO's request, when captured
  SlaveRef slave;
  CoeEmergency emergency;  // Emergency
  std::uint16_t index = 0;
  std::uint8_t subindex = 0;
  std::optional<std::uint64_t> value;  // SdoUpload, SdoDownload: when at most 8 bytes
  std::uint32_t size = 0;              // bytes transferred
  std::uint32_t abort_code = 0;        // SdoAbort
};
const char* driveMessageKindName(DriveMessage::Kind kind);  // "emergency", "sdo-upload", …
// One line for a person: "emergency 0x8611 following error too large (register 0x21, data
// 0d00000000)", "SDO upload 0x1003:1 = 0x0D218611 (pre-defined error field: error 13, class 0x21,
// 0x8611 following error too large)", "SDO abort 0x1003:2: 0x08000024 no data available".
std::string describeDriveMessage(const DriveMessage& message);
// The error history entry an answer carries: a value of 1003h:01..08 (docs/drive-messages.md).
std::optional<diag::ErrorFieldEntry> errorHistoryEntry(const DriveMessage& message);

// What could not be decoded as it should (hostile or damaged input).
struct MailboxNote {
  std::uint64_t frame = 0;
  SlaveRef slave;
  std::string text;
};

// Messages seen, by mailbox type and CoE service (other protocols are only counted).
struct MailboxCounts {
  std::uint64_t messages = 0;  // all decoded mailboxes, requests and answers
  std::uint64_t coe = 0, eoe = 0, foe = 0, soe = 0, aoe = 0, voe = 0, other = 0;
  std::uint64_t emergencies = 0;
  std::uint64_t sdo_answers = 0;   // responses and aborts paired or not
  std::uint64_t sdo_unpaired = 0;  // answers whose request the capture did not hold
  std::uint64_t repeats = 0;       // a read of a message already read (same counter)
  std::uint64_t sdo_information = 0;
};

class MailboxTracker {
 public:
  static constexpr std::size_t kMaxPending = 4;
  static constexpr std::uint32_t kMaxTransferBytes = 1u << 20;
  static constexpr std::size_t kMaxMessages = 10'000;
  static constexpr std::size_t kMaxNotes = 64;

  // The mailbox areas a configuration tool set (an ENI), used for a slave whose start-up the
  // capture does not hold (PROTOCOL.md §11: the start-up's SM writes, else these, else seen).
  void configure(std::vector<MailboxArea> areas) { configured_ = std::move(areas); }

  // Every walked frame (Ok or Truncated) in capture order, `addressing.beginFrame` called for it.
  // Events for the rules (emergencies, aborts, 1003h shrinking) are appended to `out`.
  // `now` on the segment's clock (the events'), `time_ns` the frame's own timestamp (the
  // messages').
  void onFrame(const EcatFrame& frame, const ByteReader& bytes, const FrameAddressing& addressing,
               const Stamp& now, std::int64_t time_ns, std::vector<BusEvent>& out);

  // A frame with no register command: nothing said in it.
  void quietFrame() {
    if (!frame_messages_.empty()) frame_messages_.clear();
  }

  // The messages, in frame order (at most kMaxMessages, the rest counted in omitted()).
  const std::vector<DriveMessage>& messages() const { return messages_; }
  std::uint64_t omitted() const { return omitted_; }
  // The last frame's messages (the plugin's fields).
  const std::vector<DriveMessage>& frameMessages() const { return frame_messages_; }
  const std::vector<MailboxNote>& notes() const { return notes_; }
  std::uint64_t notesOmitted() const { return notes_omitted_; }
  const MailboxCounts& counts() const { return counts_; }

 private:
  struct Pending {
    std::uint16_t index = 0;
    std::uint8_t subindex = 0;
    bool upload = true;
    std::uint64_t frame = 0;
    std::optional<std::uint64_t> value;  // a download's
    std::uint32_t size = 0;
  };
  struct Transfer {
    std::uint16_t index = 0;
    std::uint8_t subindex = 0;
    std::optional<std::uint64_t> request_frame;
    std::optional<std::uint32_t> size;  // declared
    std::uint32_t received = 0;
    std::array<std::uint8_t, 8> first{};
    bool toggle = false;  // the next segment's
  };
  struct MbxData {
    std::array<std::uint8_t, 16> sm{};  // SM0 and SM1 as written
    std::bitset<16> sm_known;
    std::optional<std::uint16_t> out_seen, in_seen;  // seen in use
    std::array<Pending, kMaxPending> pending{};
    std::size_t pending_count = 0;
    std::optional<Transfer> transfer;
    std::optional<std::uint8_t> last_counter;
    std::optional<std::uint32_t> error_count;  // 1003h:0 as last read
    Stamp error_count_at;
    bool cleared = false;       // 1003h:0 written 0 since
    bool length_noted = false;  // one note of a mailbox too long per slave
    void absorb(const MbxData& other);
  };
  using Slave = SlaveDirectory<MbxData>::Slave;

  // The SM0 (`in` false) or SM1 start the start-up configured as a mailbox, else the ENI's, else
  // the one seen.
  std::optional<std::uint16_t> areaOf(const Slave& slave, bool in) const;
  const MailboxArea* configuredFor(std::uint16_t station) const;
  void onSmWrite(MbxData& data, const Datagram& dg, const ByteReader& bytes);
  void onMailbox(Slave& slave, const MailboxMessage& m, const ByteReader& bytes, bool in,
                 std::vector<BusEvent>& out);
  void onRequest(Slave& slave, const SdoMessage& sdo);
  void onAnswer(Slave& slave, const SdoMessage& sdo, const ByteReader& bytes,
                std::vector<BusEvent>& out);
  void onSegment(Slave& slave, const SdoMessage& sdo, const ByteReader& bytes,
                 std::vector<BusEvent>& out);
  void onUploaded(Slave& slave, DriveMessage& message, std::vector<BusEvent>& out);
  std::optional<Pending> takePending(MbxData& data, std::uint16_t index, std::uint8_t sub,
                                     bool upload);
  void emit(DriveMessage message);
  void note(const Slave& slave, std::string text);
  SlaveRef refOf(const Slave& slave) const { return SlaveRef{slave.station, slave.position}; }

  SlaveDirectory<MbxData> directory_;
  std::vector<MailboxArea> configured_;
  std::vector<DriveMessage> messages_;
  std::uint64_t omitted_ = 0;
  std::vector<DriveMessage> frame_messages_;
  std::vector<MailboxNote> notes_;
  std::uint64_t notes_omitted_ = 0;
  MailboxCounts counts_;
  Stamp now_;
  std::uint64_t frame_ = 0;
  std::int64_t time_ns_ = 0;
};

}  // namespace ncservo
