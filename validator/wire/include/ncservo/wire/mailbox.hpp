// One mailbox message as captured (PROTOCOL.md §11, ETG.1000.4 mailbox, ETG.1000.6 CoE): its
// header, and for CoE the emergency or the SDO it holds. A decoder of untrusted bytes: every read
// goes through the ByteReader, the message's own length is checked against the datagram's
// captured data, nothing is allocated and nothing is kept (pairing answers with requests is the
// model's, model/mailbox_tracker.hpp).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>

#include "ncservo/base/byte_reader.hpp"

namespace ncservo {

enum class MailboxStatus : std::uint8_t {
  NotMailbox,        // fewer bytes than a header, or a length of zero: nothing in it
  Ok,                // decoded (an unknown type or CoE service is Ok with nothing more)
  LengthBeyondData,  // the header's length runs past the datagram's data: not decoded
  Short,             // a CoE message shorter than its service needs: not decoded
};

struct CoeEmergency {
  std::uint16_t code = 0;
  std::uint8_t error_register = 0;
  std::array<std::uint8_t, 5> data{};
};

enum class SdoKind : std::uint8_t {
  InitiateDownload,
  DownloadSegment,
  InitiateUpload,
  UploadSegment,
  Abort,
  Unknown,  // a command specifier the direction does not define
};
const char* sdoKindName(SdoKind kind);

struct SdoMessage {
  bool request = true;  // written by the master (SM0), else read back (SM1)
  SdoKind kind = SdoKind::Unknown;
  std::uint8_t command = 0;
  // Initiate and abort: the object; segments have none.
  std::uint16_t index = 0;
  std::uint8_t subindex = 0;
  bool complete_access = false;
  bool expedited = false;
  // Initiate with data (download request, upload response): the size of the whole transfer in
  // bytes when indicated (expedited: 4 minus the unused bytes).
  std::optional<std::uint32_t> size;
  // The value, when this message holds all of it in at most 8 bytes (expedited, or a normal
  // transfer whose data fits in this message).
  std::optional<std::uint64_t> value;
  // The data this message carries (a normal initiate's first part, or a segment's): where in the
  // captured bytes, and how many (within the mailbox's length and the capture).
  std::size_t data_at = 0;
  std::size_t data_size = 0;
  bool toggle = false;  // segments
  bool last = false;    // segments: no more follow
  std::uint32_t abort_code = 0;
};

struct MailboxMessage {
  MailboxStatus status = MailboxStatus::NotMailbox;
  std::uint16_t length = 0;  // of what follows the 6-byte header
  std::uint16_t address = 0;
  std::uint8_t channel = 0;
  std::uint8_t priority = 0;
  std::uint8_t type = 0;
  std::uint8_t counter = 0;
  std::size_t available = 0;  // bytes of the datagram's data (for LengthBeyondData)
  // CoE only.
  std::uint16_t coe_number = 0;
  std::uint8_t coe_service = 0;
  std::optional<CoeEmergency> emergency;
  std::optional<SdoMessage> sdo;

  bool isCoe() const;
};

// The mailbox at `offset` of `bytes`, of which `available` bytes belong to the datagram (its
// captured data). An SDO's command specifier reads as a request or a response as its CoE service
// says (2 request, 3 response).
MailboxMessage decodeMailbox(const ByteReader& bytes, std::size_t offset, std::size_t available);

// Whether the bytes look like the start of a mailbox message, for finding a slave's mailbox
// where no start-up configured it ("seen in use"): a length that fits, a known type, a CoE
// service that exists and a zero reserved byte.
bool looksLikeMailbox(const ByteReader& bytes, std::size_t offset, std::size_t available);

}  // namespace ncservo
