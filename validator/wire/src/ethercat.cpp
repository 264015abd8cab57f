#include "ncservo/wire/ethercat.hpp"

namespace ncservo {

namespace {
// Follows a payload of EtherType `type` at `payload` (VLAN tags, IP/UDP) to the EtherCAT header.
void walkPayload(const ByteReader& bytes, std::uint16_t type, std::size_t payload, EcatFrame& out) {
  out.status = WalkStatus::NotEtherCat;
  // A VLAN tag is 2 bytes of TCI and then the next EtherType; tags may stack (802.1ad).
  while (type == ecat::kEtherTypeVlan || type == ecat::kEtherTypeQinQ ||
         type == ecat::kEtherTypeQinQOld) {
    auto inner = bytes.be16(payload + 2);
    if (!inner) return;
    type = *inner;
    payload += ecat::kVlanTagSize;
  }
  if (type == ecat::kEtherType) {
    walkEcat(bytes, payload, out);
    return;
  }
  std::size_t udp = 0;
  if (type == ecat::kEtherTypeIpv4) {
    auto version_ihl = bytes.u8(payload);
    auto fragment = bytes.be16(payload + 6);
    auto protocol = bytes.u8(payload + 9);
    if (!version_ihl || !fragment || !protocol) return;
    std::size_t ihl = (*version_ihl & 0x0F) * 4u;
    bool first_fragment = (*fragment & 0x1FFF) == 0;
    if ((*version_ihl >> 4) != 4 || ihl < ecat::kIpv4MinHeaderSize ||
        *protocol != ecat::kIpProtoUdp || !first_fragment) {
      return;
    }
    udp = payload + ihl;
  } else if (type == ecat::kEtherTypeIpv6) {
    auto next_header = bytes.u8(payload + 6);
    if (!next_header || *next_header != ecat::kIpProtoUdp) return;
    udp = payload + ecat::kIpv6HeaderSize;
  } else {
    return;
  }
  auto dst_port = bytes.be16(udp + 2);
  if (!dst_port || *dst_port != ecat::kUdpPort) return;
  walkEcat(bytes, udp + ecat::kUdpHeaderSize, out);
}

void walkFromTypeField(const ByteReader& bytes, std::size_t type_offset, std::size_t payload,
                       EcatFrame& out) {
  auto type = bytes.be16(type_offset);
  if (!type) {
    out.status = WalkStatus::NotEtherCat;
    return;
  }
  walkPayload(bytes, *type, payload, out);
}

// The ESL header at `offset`, if its 6 fixed bytes are there (docs/protocol.md §8).
std::optional<ProbeHeader> eslHeaderAt(const ByteReader& bytes, std::size_t offset) {
  const std::optional<ByteRecord<esl::kHeaderSize>> header = bytes.record<esl::kHeaderSize>(offset);
  if (!header) return std::nullopt;
  const std::uint8_t* magic = bytes.data() + offset;  // inside the record just read
  for (std::size_t i = 0; i < esl::kMagic.size(); ++i) {
    const bool variant = i == esl::kMagicVariantAt && magic[i] == esl::kMagicVariant;
    if (magic[i] != esl::kMagic[i] && !variant) return std::nullopt;
  }
  ProbeHeader probe;
  probe.present = true;
  probe.flags = header->le16<esl::kFlagsOffset>();
  probe.timestamp_ns = header->le64<esl::kTimestampOffset>();
  return probe;
}

void walkEthernet(const ByteReader& bytes, std::size_t start, EcatFrame& out) {
  walkFromTypeField(bytes, start + ecat::kEthernetHeaderSize - 2, start + ecat::kEthernetHeaderSize,
                    out);
}

// An Ethernet frame, with the probe's ESL header before it or appended after it.
void walkProbedEthernet(const ByteReader& bytes, EcatFrame& out) {
  if (std::optional<ProbeHeader> before = eslHeaderAt(bytes, 0)) {
    out.probe = *before;
    out.probe.before = true;
    walkEthernet(bytes, esl::kHeaderSize, out);
    return;
  }
  const std::size_t size = bytes.size();
  std::optional<ProbeHeader> after;
  if (size >= ecat::kEthernetHeaderSize + esl::kHeaderSize) {
    after = eslHeaderAt(bytes, size - esl::kHeaderSize);
  }
  if (after) {
    // The same six bytes may end an ordinary frame's data: taken as a header only when the
    // EtherCAT frame ends before it.
    walkEthernet(ByteReader(bytes.data(), size - esl::kHeaderSize), 0, out);
    if (out.status != WalkStatus::Truncated) {
      out.probe = *after;
      return;
    }
  }
  walkEthernet(bytes, 0, out);
}
}  // namespace

LinkType linkTypeFromDlt(int dlt) {
  switch (dlt) {
    case ecat::kDltEthernet:
      return LinkType::Ethernet;
    case ecat::kDltLinuxSll:
      return LinkType::LinuxSll;
    case ecat::kDltLinuxSll2:
      return LinkType::LinuxSll2;
    default:
      return LinkType::Unsupported;
  }
}

void walkEcat(const ByteReader& bytes, std::size_t offset, EcatFrame& out) {
  out.ecat_offset = offset;
  out.count = 0;
  out.chain_length = 0;
  out.truncated_at = 0;
  auto frame_header = bytes.le16(offset);
  if (!frame_header) {
    out.status = WalkStatus::Truncated;
    out.truncated_at = bytes.size();
    return;
  }
  out.header_length = *frame_header & ecat::kLengthMask;
  if ((*frame_header >> ecat::kFrameTypeShift) != ecat::kFrameTypeDatagrams) {
    out.status = WalkStatus::NotDatagrams;
    return;
  }
  out.status = WalkStatus::Ok;
  const std::size_t chain_start = offset + ecat::kFrameHeaderSize;
  std::size_t pos = chain_start;
  bool more = true;
  // Each datagram advances pos by at least 12 bytes, so the loop ends; the chain is bounded by
  // the captured bytes, not by the header's length (which may be larger than the chain).
  while (more && out.count < out.datagrams.size()) {
    const std::optional<ByteRecord<ecat::kDatagramHeaderSize>> header =
        bytes.record<ecat::kDatagramHeaderSize>(pos);
    if (!header) {
      out.status = WalkStatus::Truncated;
      out.truncated_at = bytes.size();
      break;
    }
    const std::uint16_t length_word = header->le16<ecat::kDatagramLengthWordAt>();
    Datagram& dg = out.datagrams[out.count];
    dg.command = header->u8<ecat::kDatagramCommandAt>();
    dg.index = header->u8<ecat::kDatagramIndexAt>();
    dg.address = header->le32<ecat::kDatagramAddressAt>();
    dg.length = length_word & ecat::kLengthMask;
    dg.circulating = (length_word & ecat::kCirculatingBit) != 0;
    more = (length_word & ecat::kMoreBit) != 0;
    dg.irq = header->le16<ecat::kDatagramIrqAt>();
    dg.header_offset = pos;
    dg.data_offset = pos + ecat::kDatagramHeaderSize;
    const std::size_t available = bytes.size() - dg.data_offset;  // has() above: no underflow
    dg.data_captured = dg.length <= available ? dg.length : available;
    ++out.count;
    const std::optional<std::uint16_t> wkc = bytes.le16(dg.data_offset + dg.length);
    dg.has_wkc = wkc.has_value();
    dg.wkc = wkc.value_or(0);
    if (!wkc) {  // the data or the working counter is cut short
      out.status = WalkStatus::Truncated;
      out.truncated_at = bytes.size();
      break;
    }
    pos = dg.data_offset + dg.length + ecat::kWkcSize;
  }
  out.chain_length = pos - chain_start;
}

void walkPacket(LinkType link, const ByteReader& bytes, EcatFrame& out) {
  out.count = 0;
  out.status = WalkStatus::NotEtherCat;
  out.probe = ProbeHeader{};
  switch (link) {
    case LinkType::Ethernet:
      walkProbedEthernet(bytes, out);
      // A frame the probe saw with a CRC error is a bus fault, not process data (§8).
      if (out.probe.crcError() && out.status != WalkStatus::NotEtherCat) {
        out.status = WalkStatus::BusFault;
      }
      return;
    case LinkType::LinuxSll:
      walkFromTypeField(bytes, ecat::kSllHeaderSize - 2, ecat::kSllHeaderSize, out);
      return;
    case LinkType::LinuxSll2:  // the protocol type comes first in SLL2
      walkFromTypeField(bytes, 0, ecat::kSll2HeaderSize, out);
      return;
    case LinkType::Unsupported:
      return;
  }
}

bool EcatFrame::sameDatagramList(const EcatFrame& other) const {
  if (count != other.count) return false;
  for (std::size_t i = 0; i < count; ++i) {
    const Datagram& a = datagrams[i];
    const Datagram& b = other.datagrams[i];
    if (a.command != b.command || a.index != b.index || a.length != b.length) return false;
    if (ecat::addressSurvivesRing(a.command) && a.address != b.address) {
      return false;
    }
  }
  return true;
}

bool EcatFrame::mayCarryProcessData() const {
  for (std::size_t i = 0; i < count; ++i) {
    const Datagram& dg = datagrams[i];
    if (ecat::isLogical(dg.command) ||
        (ecat::isConfiguredAddress(dg.command) && dg.ado() >= ecat::kProcessRam)) {
      return true;
    }
  }
  return false;
}

bool EcatFrame::anyWkcAboveZero() const {
  for (std::size_t i = 0; i < count; ++i) {
    if (datagrams[i].has_wkc && datagrams[i].wkc > 0) return true;
  }
  return false;
}

}  // namespace ncservo
