#include "ncservo/wire/coe_pdo.hpp"

#include <algorithm>

#include "ncservo/wire/ecat_wire.hpp"

namespace ncservo {
namespace {

// Where the SDO starts in a mailbox: after the mailbox and CoE headers.
constexpr std::size_t kSdo = ecat::kMailboxHeaderSize + ecat::kCoeHeaderSize;

bool isAssignment(std::uint16_t index) {
  return index == ecat::kRxPdoAssignment || index == ecat::kTxPdoAssignment;
}
bool kept(std::uint16_t index) {
  return isAssignment(index) ||
         (index >= ecat::kRxPdoMappingFirst && index <= ecat::kRxPdoMappingLast) ||
         (index >= ecat::kTxPdoMappingFirst && index <= ecat::kTxPdoMappingLast);
}

}  // namespace

void CoePdoObjects::store(std::uint16_t index, std::uint8_t sub, std::uint32_t value) {
  if (!kept(index)) return;
  for (Entry& e : entries_) {
    if (e.index == index && e.sub == sub) {
      e.value = value;
      return;
    }
  }
  if (entries_.size() < kMaxEntries) entries_.push_back({index, sub, value});
}

void CoePdoObjects::storeComplete(std::uint16_t index, std::uint8_t sub, const ByteReader& bytes,
                                  std::size_t at, std::size_t size) {
  const std::size_t end = at + size;
  const std::size_t width = isAssignment(index) ? 2 : 4;
  std::uint32_t next = sub;
  if (sub == 0) {
    auto count = bytes.u8(at);
    if (!count || size < 2) return;
    store(index, 0, *count);
    at += 2;  // subindex 0 is one byte, padded to 16 bits
    next = 1;
  }
  for (; at + width <= end && next <= 0xFF; at += width, ++next) {
    auto v = width == 2 ? std::optional<std::uint32_t>(bytes.le16(at)) : bytes.le32(at);
    if (!v) return;
    store(index, static_cast<std::uint8_t>(next), *v);
  }
}

void CoePdoObjects::onMailbox(const ByteReader& bytes, std::size_t offset, std::size_t length,
                              bool request) {
  auto mailbox_length = bytes.le16(offset + ecat::kMailboxLengthAt);
  auto type = bytes.u8(offset + ecat::kMailboxTypeAt);
  auto coe = bytes.le16(offset + ecat::kMailboxHeaderSize);
  auto command = bytes.u8(offset + kSdo + ecat::kSdoCommandAt);
  auto index = bytes.le16(offset + kSdo + ecat::kSdoIndexAt);
  auto sub = bytes.u8(offset + kSdo + ecat::kSdoSubindexAt);
  if (!mailbox_length || !type || !coe || !command || !index || !sub) return;
  if ((*type & ecat::kMailboxTypeMask) != ecat::kMailboxTypeCoe || !kept(*index)) return;
  // The mailbox's own length (after its header) bounds what is read, as does the capture.
  const std::size_t end =
      offset + std::min<std::size_t>(ecat::kMailboxHeaderSize + *mailbox_length, length);
  const std::uint8_t service = static_cast<std::uint8_t>(*coe >> ecat::kCoeServiceShift);
  const std::uint8_t specifier = static_cast<std::uint8_t>(*command >> ecat::kSdoSpecifierShift);
  const bool takes = request ? service == ecat::kCoeServiceSdoRequest &&
                                   specifier == ecat::kSdoInitiateDownloadRequest
                             : service == ecat::kCoeServiceSdoResponse &&
                                   specifier == ecat::kSdoInitiateUploadResponse;
  if (!takes) return;
  const std::size_t data = offset + kSdo + ecat::kSdoDataAt;
  if (*command & ecat::kSdoExpedited) {
    const std::size_t size = (*command & ecat::kSdoSizeIndicated)
                                 ? ecat::kSdoDataSize - ((*command >> ecat::kSdoUnusedBytesShift) &
                                                         ecat::kSdoUnusedBytesMask)
                                 : ecat::kSdoDataSize;
    if (data + size > end) return;
    const auto value = bytes.le(data, size);
    if (!value) return;
    if (*command & ecat::kSdoCompleteAccess) {
      storeComplete(*index, *sub, ByteReader(bytes.data(), std::min(end, bytes.size())), data,
                    size);
    } else {
      store(*index, *sub, static_cast<std::uint32_t>(*value));
    }
    return;
  }
  // Normal transfer: a 4-byte size, then as much of the data as this mailbox holds.
  auto size = bytes.le32(data);
  if (!size) return;
  const std::size_t first = data + ecat::kSdoDataSize;
  if (first > end) return;
  const std::size_t here = std::min<std::size_t>(*size, end - first);
  const ByteReader bounded(bytes.data(), std::min(end, bytes.size()));
  if (*command & ecat::kSdoCompleteAccess) {
    storeComplete(*index, *sub, bounded, first, here);
  } else if (here >= 1 && here <= 4) {
    const auto value = bounded.le(first, here);
    if (!value) return;
    store(*index, *sub, static_cast<std::uint32_t>(*value));
  }
}

std::optional<std::uint32_t> CoePdoObjects::value(std::uint16_t index, std::uint8_t sub) const {
  for (const Entry& e : entries_) {
    if (e.index == index && e.sub == sub) return e.value;
  }
  return std::nullopt;
}

std::optional<std::uint32_t> CoePdoObjects::assignedBits(std::uint16_t assignment) const {
  auto count = value(assignment, 0);
  if (!count) return std::nullopt;
  std::uint32_t bits = 0;
  for (std::uint32_t i = 1; i <= (*count & 0xFF); ++i) {
    auto pdo = value(assignment, static_cast<std::uint8_t>(i));
    if (!pdo) return std::nullopt;
    auto entries = value(static_cast<std::uint16_t>(*pdo), 0);
    if (!entries) return std::nullopt;
    for (std::uint32_t k = 1; k <= (*entries & 0xFF); ++k) {
      auto entry = value(static_cast<std::uint16_t>(*pdo), static_cast<std::uint8_t>(k));
      if (!entry) return std::nullopt;
      bits += *entry & ecat::kPdoEntryBitsMask;
    }
  }
  return bits;
}

void CoePdoObjects::absorb(const CoePdoObjects& other) {
  for (const Entry& e : other.entries_) {
    if (!value(e.index, e.sub)) store(e.index, e.sub, e.value);
  }
}

}  // namespace ncservo
