#include "ncservo/wire/mailbox.hpp"

#include <algorithm>

#include "ncservo/wire/ecat_wire.hpp"

namespace ncservo {
namespace {

constexpr std::size_t kCoeAt = ecat::kMailboxHeaderSize;
constexpr std::size_t kBodyAt = ecat::kMailboxHeaderSize + ecat::kCoeHeaderSize;

SdoKind kindOf(std::uint8_t specifier, bool request) {
  if (specifier == ecat::kSdoAbort) return SdoKind::Abort;
  if (request) {
    switch (specifier) {
      case ecat::kSdoDownloadSegmentRequest:
        return SdoKind::DownloadSegment;
      case ecat::kSdoInitiateDownloadRequest:
        return SdoKind::InitiateDownload;
      case ecat::kSdoInitiateUploadRequest:
        return SdoKind::InitiateUpload;
      case ecat::kSdoUploadSegmentRequest:
        return SdoKind::UploadSegment;
      default:
        return SdoKind::Unknown;
    }
  }
  switch (specifier) {
    case ecat::kSdoUploadSegmentResponse:
      return SdoKind::UploadSegment;
    case ecat::kSdoDownloadSegmentResponse:
      return SdoKind::DownloadSegment;
    case ecat::kSdoInitiateUploadResponse:
      return SdoKind::InitiateUpload;
    case ecat::kSdoInitiateDownloadResponse:
      return SdoKind::InitiateDownload;
    default:
      return SdoKind::Unknown;
  }
}

// The SDO in [at, end) of `bytes` (end within the mailbox's length and the capture).
std::optional<SdoMessage> decodeSdo(const ByteReader& bytes, std::size_t at, std::size_t end,
                                    bool request) {
  auto command = bytes.u8(at + ecat::kSdoCommandAt);
  if (!command || at + 1 > end) return std::nullopt;
  SdoMessage sdo;
  sdo.request = request;
  sdo.command = *command;
  sdo.kind = kindOf(static_cast<std::uint8_t>(*command >> ecat::kSdoSpecifierShift), request);
  const bool segment = sdo.kind == SdoKind::DownloadSegment || sdo.kind == SdoKind::UploadSegment;
  if (segment) {
    sdo.toggle = (*command & ecat::kSdoToggle) != 0;
    // Only a segment with data (a download request, an upload response) has the unused bytes
    // and the last-segment bit; the other direction's command byte is padded to 7 bytes.
    const bool carries = request == (sdo.kind == SdoKind::DownloadSegment);
    if (!carries) return sdo;
    sdo.last = (*command & ecat::kSdoLastSegment) != 0;
    const std::size_t data = at + ecat::kSdoSegmentDataAt;
    if (data > end) return std::nullopt;
    const std::size_t room = end - data;
    std::size_t size = room;
    if (room <= ecat::kSdoSegmentMinData) {
      const std::size_t unused =
          (*command >> ecat::kSdoSegmentUnusedShift) & ecat::kSdoSegmentUnusedMask;
      size = std::min(room, ecat::kSdoSegmentMinData - std::min(unused, ecat::kSdoSegmentMinData));
    }
    sdo.data_at = data;
    sdo.data_size = size;
    if (size <= 8) sdo.value = bytes.le(data, size);
    return sdo;
  }
  auto index = bytes.le16(at + ecat::kSdoIndexAt);
  auto sub = bytes.u8(at + ecat::kSdoSubindexAt);
  if (!index || !sub || at + ecat::kSdoDataAt > end) return std::nullopt;
  sdo.index = *index;
  sdo.subindex = *sub;
  sdo.complete_access = (*command & ecat::kSdoCompleteAccess) != 0;
  const std::size_t data = at + ecat::kSdoDataAt;
  if (sdo.kind == SdoKind::Abort) {
    auto code = data + 4 <= end ? bytes.le32(data) : std::nullopt;
    if (!code) return std::nullopt;
    sdo.abort_code = *code;
    return sdo;
  }
  const bool carries = request == (sdo.kind == SdoKind::InitiateDownload);
  if (!carries || sdo.kind == SdoKind::Unknown) return sdo;
  sdo.expedited = (*command & ecat::kSdoExpedited) != 0;
  const bool indicated = (*command & ecat::kSdoSizeIndicated) != 0;
  if (sdo.expedited) {
    const std::size_t size =
        indicated ? ecat::kSdoDataSize -
                        ((*command >> ecat::kSdoUnusedBytesShift) & ecat::kSdoUnusedBytesMask)
                  : ecat::kSdoDataSize;
    if (data + size > end) return std::nullopt;
    sdo.size = static_cast<std::uint32_t>(size);
    sdo.data_at = data;
    sdo.data_size = size;
    sdo.value = bytes.le(data, size);
    return sdo.value ? std::optional<SdoMessage>(sdo) : std::nullopt;
  }
  // Normal transfer: a 4-byte size, then as much of the data as this mailbox holds.
  auto size = data + ecat::kSdoDataSize <= end ? bytes.le32(data) : std::nullopt;
  if (!size) return std::nullopt;
  sdo.size = *size;
  const std::size_t first = data + ecat::kSdoDataSize;
  sdo.data_at = first;
  sdo.data_size = std::min<std::size_t>(*size, end - first);
  if (sdo.data_size == *size && *size <= 8 && *size > 0) sdo.value = bytes.le(first, *size);
  return sdo;
}

}  // namespace

const char* sdoKindName(SdoKind kind) {
  switch (kind) {
    case SdoKind::InitiateDownload:
      return "initiate download";
    case SdoKind::DownloadSegment:
      return "download segment";
    case SdoKind::InitiateUpload:
      return "initiate upload";
    case SdoKind::UploadSegment:
      return "upload segment";
    case SdoKind::Abort:
      return "abort";
    case SdoKind::Unknown:
      break;
  }
  return "unknown";
}

bool MailboxMessage::isCoe() const {
  return status == MailboxStatus::Ok && type == ecat::kMailboxTypeCoe;
}

MailboxMessage decodeMailbox(const ByteReader& bytes, std::size_t offset, std::size_t available) {
  MailboxMessage m;
  m.available = available;
  auto header = available >= ecat::kMailboxHeaderSize
                    ? bytes.record<ecat::kMailboxHeaderSize>(offset)
                    : std::nullopt;
  if (!header) return m;
  m.length = header->le16<ecat::kMailboxLengthAt>();
  m.address = header->le16<ecat::kMailboxAddressAt>();
  const std::uint8_t channel = header->u8<ecat::kMailboxChannelAt>();
  m.channel = channel & ecat::kMailboxChannelMask;
  m.priority = static_cast<std::uint8_t>(channel >> ecat::kMailboxPriorityShift);
  const std::uint8_t type = header->u8<ecat::kMailboxTypeAt>();
  m.type = type & ecat::kMailboxTypeMask;
  m.counter = (type >> ecat::kMailboxCounterShift) & ecat::kMailboxCounterMask;
  if (m.length == 0) return m;
  if (std::size_t{m.length} > available - ecat::kMailboxHeaderSize) {
    m.status = MailboxStatus::LengthBeyondData;
    return m;
  }
  m.status = MailboxStatus::Ok;
  if (m.type != ecat::kMailboxTypeCoe) return m;
  const std::size_t end = offset + ecat::kMailboxHeaderSize + m.length;
  auto coe = m.length >= ecat::kCoeHeaderSize ? bytes.le16(offset + kCoeAt) : std::nullopt;
  if (!coe) {
    m.status = MailboxStatus::Short;
    return m;
  }
  m.coe_number = *coe & ecat::kCoeNumberMask;
  m.coe_service = static_cast<std::uint8_t>(*coe >> ecat::kCoeServiceShift);
  const std::size_t body = offset + kBodyAt;
  if (m.coe_service == ecat::kCoeServiceEmergency) {
    auto e = body + ecat::kEmcySize <= end ? bytes.record<ecat::kEmcySize>(body) : std::nullopt;
    if (!e) {
      m.status = MailboxStatus::Short;
      return m;
    }
    CoeEmergency emergency;
    emergency.code = e->le16<ecat::kEmcyCodeAt>();
    emergency.error_register = e->u8<ecat::kEmcyRegisterAt>();
    emergency.data = {e->u8<ecat::kEmcyDataAt>(), e->u8<ecat::kEmcyDataAt + 1>(),
                      e->u8<ecat::kEmcyDataAt + 2>(), e->u8<ecat::kEmcyDataAt + 3>(),
                      e->u8<ecat::kEmcyDataAt + 4>()};
    m.emergency = emergency;
  } else if (m.coe_service == ecat::kCoeServiceSdoRequest ||
             m.coe_service == ecat::kCoeServiceSdoResponse) {
    // The service says the direction; SM0 and SM1 should agree with it.
    m.sdo = decodeSdo(bytes, body, std::min(end, bytes.size()),
                      m.coe_service == ecat::kCoeServiceSdoRequest);
    if (!m.sdo) m.status = MailboxStatus::Short;
  }
  return m;
}

bool looksLikeMailbox(const ByteReader& bytes, std::size_t offset, std::size_t available) {
  const MailboxMessage m = decodeMailbox(bytes, offset, available);
  if (m.status != MailboxStatus::Ok) return false;
  auto reserved = bytes.u8(offset + ecat::kMailboxChannelAt);
  if (!reserved || (*reserved & ecat::kMailboxChannelMask) != 0) return false;
  switch (m.type) {
    case ecat::kMailboxTypeCoe:
      return m.coe_service == ecat::kCoeServiceEmergency ||
             (m.sdo && m.sdo->kind != SdoKind::Unknown) ||
             m.coe_service == ecat::kCoeServiceSdoInformation;
    case ecat::kMailboxTypeAoe:
    case ecat::kMailboxTypeEoe:
    case ecat::kMailboxTypeFoe:
    case ecat::kMailboxTypeSoe:
    case ecat::kMailboxTypeVoe:
      return true;
    default:
      return false;
  }
}

}  // namespace ncservo
