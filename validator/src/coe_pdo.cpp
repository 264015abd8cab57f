#include "ncservo/coe_pdo.hpp"

#include <algorithm>

namespace ncservo {
namespace {

// Mailbox header (6 bytes): length, address, channel/priority, type (low 4 bits; 3 = CoE) and
// counter; then the CoE header (2 bytes: number, service in the top 4 bits: 2 SDO request,
// 3 SDO response); then the SDO: command, index, subindex, 4 data bytes.
constexpr std::size_t kMailboxHeader = 6;
constexpr std::size_t kCoeHeader = 2;
constexpr std::size_t kSdo = kMailboxHeader + kCoeHeader;
constexpr std::uint8_t kTypeCoe = 3;
constexpr std::uint8_t kServiceSdoRequest = 2, kServiceSdoResponse = 3;
constexpr std::uint8_t kDownloadRequest = 1;  // command specifier of an initiate download
constexpr std::uint8_t kUploadResponse = 2;   // of an initiate upload response
constexpr std::uint8_t kExpedited = 0x02, kSizeIndicated = 0x01, kCompleteAccess = 0x10;

bool kept(std::uint16_t index) {
  return index == 0x1C12 || index == 0x1C13 || (index >= 0x1600 && index <= 0x17FF) ||
         (index >= 0x1A00 && index <= 0x1BFF);
}
bool isAssignment(std::uint16_t index) {
  return index == 0x1C12 || index == 0x1C13;
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
  auto mailbox_length = bytes.le16(offset);
  auto type = bytes.u8(offset + 5);
  auto coe = bytes.le16(offset + kMailboxHeader);
  auto command = bytes.u8(offset + kSdo);
  auto index = bytes.le16(offset + kSdo + 1);
  auto sub = bytes.u8(offset + kSdo + 3);
  if (!mailbox_length || !type || !coe || !command || !index || !sub) return;
  if ((*type & 0x0F) != kTypeCoe || !kept(*index)) return;
  // The mailbox's own length (after its header) bounds what is read, as does the capture.
  const std::size_t end = offset + std::min<std::size_t>(kMailboxHeader + *mailbox_length, length);
  const std::uint8_t service = static_cast<std::uint8_t>(*coe >> 12);
  const std::uint8_t specifier = static_cast<std::uint8_t>(*command >> 5);
  const bool takes = request ? service == kServiceSdoRequest && specifier == kDownloadRequest
                             : service == kServiceSdoResponse && specifier == kUploadResponse;
  if (!takes) return;
  const std::size_t data = offset + kSdo + 4;
  if (*command & kExpedited) {
    const std::size_t size = (*command & kSizeIndicated) ? 4 - ((*command >> 2) & 3) : 4;
    if (data + size > end) return;
    std::uint32_t value = 0;
    for (std::size_t i = 0; i < size; ++i) {
      auto b = bytes.u8(data + i);
      if (!b) return;
      value |= std::uint32_t{*b} << (8 * i);
    }
    if (*command & kCompleteAccess) {
      storeComplete(*index, *sub, ByteReader(bytes.data(), std::min(end, bytes.size())), data,
                    size);
    } else {
      store(*index, *sub, value);
    }
    return;
  }
  // Normal transfer: a 4-byte size, then as much of the data as this mailbox holds.
  auto size = bytes.le32(data);
  if (!size) return;
  const std::size_t first = data + 4;
  if (first > end) return;
  const std::size_t here = std::min<std::size_t>(*size, end - first);
  const ByteReader bounded(bytes.data(), std::min(end, bytes.size()));
  if (*command & kCompleteAccess) {
    storeComplete(*index, *sub, bounded, first, here);
  } else if (here >= 1 && here <= 4) {
    std::uint32_t value = 0;
    for (std::size_t i = 0; i < here; ++i) {
      auto b = bounded.u8(first + i);
      if (!b) return;
      value |= std::uint32_t{*b} << (8 * i);
    }
    store(*index, *sub, value);
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
      bits += *entry & 0xFF;  // the entry's bit length
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
