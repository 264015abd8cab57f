#include "ncservo/model/mailbox_tracker.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstring>

#include "ncservo/base/little_endian.hpp"
#include "ncservo/wire/diagnosis_texts.hpp"

namespace ncservo {
namespace {

constexpr std::uint16_t kSmBlock = ecat::kRegSyncManager0;
constexpr std::size_t kSmBytes = 2 * ecat::kSyncManagerStride;  // SM0 and SM1

// A datagram that may carry a mailbox: a physical command to a single slave, at or above the
// process RAM (where every mailbox area lies), or one that writes SM0/SM1.
bool followed(const Datagram& dg) {
  if (ecat::isLogical(dg.command) || ecat::isBroadcast(dg.command)) return false;
  const std::size_t ado = dg.ado();
  return ado >= ecat::kProcessRam ||
         (ado < std::size_t{kSmBlock} + kSmBytes && ado + dg.data_captured > kSmBlock);
}

std::uint64_t firstBytes(const std::array<std::uint8_t, 8>& bytes, std::size_t count) {
  return loadLe(bytes.data(), std::min<std::size_t>(count, 8));
}

}  // namespace

const char* driveMessageKindName(DriveMessage::Kind kind) {
  switch (kind) {
    case DriveMessage::Kind::Emergency:
      return "emergency";
    case DriveMessage::Kind::SdoUpload:
      return "sdo-upload";
    case DriveMessage::Kind::SdoDownload:
      return "sdo-download";
    case DriveMessage::Kind::SdoAbort:
      return "sdo-abort";
  }
  return "unknown";
}

std::string describeDriveMessage(const DriveMessage& m) {
  auto text = [](const char* t) { return t ? fmt::format(" {}", t) : std::string(); };
  switch (m.kind) {
    case DriveMessage::Kind::Emergency: {
      std::string data;
      for (std::uint8_t b : m.emergency.data) data += fmt::format("{:02x}", b);
      return fmt::format("emergency 0x{:04X}{} (register 0x{:02X}, data {})", m.emergency.code,
                         text(diag::errorCodeText(m.emergency.code)), m.emergency.error_register,
                         data);
    }
    case DriveMessage::Kind::SdoAbort:
      return fmt::format("SDO abort 0x{:04X}:{}: 0x{:08X}{}", m.index, m.subindex, m.abort_code,
                         text(diag::abortText(m.abort_code)));
    case DriveMessage::Kind::SdoUpload:
    case DriveMessage::Kind::SdoDownload: {
      std::string out = fmt::format("SDO {} 0x{:04X}:{}",
                                    m.kind == DriveMessage::Kind::SdoUpload ? "upload" : "download",
                                    m.index, m.subindex);
      if (m.value) {
        out += fmt::format(" = 0x{:X}", *m.value);
      } else {
        out += fmt::format(" ({} bytes)", m.size);
      }
      if (const char* object = diag::objectName(m.index)) {
        out += fmt::format(" ({}", object);
        if (const std::optional<diag::ErrorFieldEntry> e = errorHistoryEntry(m)) {
          out += fmt::format(": error {}, class 0x{:02X}, 0x{:04X}{}", e->number, e->error_class,
                             e->code, text(diag::errorCodeText(e->code)));
        }
        out += ")";
      }
      return out;
    }
  }
  return "unknown";
}

std::optional<diag::ErrorFieldEntry> errorHistoryEntry(const DriveMessage& m) {
  if (m.kind == DriveMessage::Kind::SdoAbort || m.index != diag::kPredefinedErrorField ||
      m.subindex < 1 || !m.value) {
    return std::nullopt;
  }
  return diag::errorFieldEntry(static_cast<std::uint32_t>(*m.value));
}

void MailboxTracker::MbxData::absorb(const MbxData& other) {
  for (std::size_t i = 0; i < sm.size(); ++i) {
    if (!sm_known[i] && other.sm_known[i]) {
      sm[i] = other.sm[i];
      sm_known[i] = true;
    }
  }
  if (!out_seen) out_seen = other.out_seen;
  if (!in_seen) in_seen = other.in_seen;
  if (!error_count) {
    error_count = other.error_count;
    error_count_at = other.error_count_at;
  }
}

const MailboxArea* MailboxTracker::configuredFor(std::uint16_t station) const {
  for (const MailboxArea& area : configured_) {
    if (area.station == station) return &area;
  }
  return nullptr;
}

std::optional<std::uint16_t> MailboxTracker::areaOf(const Slave& slave, bool in) const {
  const MbxData& data = slave.data;
  const std::size_t at = in ? ecat::kSyncManagerStride : 0;
  bool known = true;
  for (std::size_t i = at; i <= at + ecat::kSmControlAt; ++i) known = known && data.sm_known[i];
  if (known && (data.sm[at + ecat::kSmControlAt] & ecat::kSmModeMask) == ecat::kSmModeMailbox) {
    return static_cast<std::uint16_t>(loadLe<2>(data.sm.data() + at + ecat::kSmStartAt));
  }
  if (const MailboxArea* area = slave.station ? configuredFor(*slave.station) : nullptr) {
    return in ? area->in_start : area->out_start;
  }
  return in ? data.in_seen : data.out_seen;
}

void MailboxTracker::onSmWrite(MbxData& data, const Datagram& dg, const ByteReader& bytes) {
  const std::size_t ado = dg.ado();
  const std::size_t from = std::max<std::size_t>(ado, kSmBlock);
  const std::size_t to = std::min<std::size_t>(ado + dg.data_captured, kSmBlock + kSmBytes);
  for (std::size_t reg = from; reg < to; ++reg) {
    auto value = bytes.u8(dg.data_offset + (reg - ado));
    if (!value) break;
    data.sm[reg - kSmBlock] = *value;
    data.sm_known[reg - kSmBlock] = true;
  }
}

void MailboxTracker::onFrame(const EcatFrame& frame, const ByteReader& bytes,
                             const FrameAddressing& addressing, const Stamp& now,
                             std::int64_t time_ns, std::vector<BusEvent>& out) {
  frame_messages_.clear();
  bool any = false;
  for (std::size_t i = 0; i < frame.count && !any; ++i) any = followed(frame.datagrams[i]);
  if (!any) return;
  now_ = now;
  frame_ = now.frame;
  time_ns_ = time_ns;
  const bool take_writes = addressing.takesWrites();
  for (std::size_t i = 0; i < frame.count; ++i) {
    const Datagram& dg = frame.datagrams[i];
    if (!followed(dg)) continue;
    const SlaveAddress address = addressing.addressOf(dg, i);
    if (address.target != SlaveTarget::Station && address.target != SlaveTarget::Position) {
      continue;
    }
    const bool writes = take_writes && ecat::writesRegisters(dg.command);
    const bool reads = addressing.takesRead(dg);
    if (writes) directory_.noteStationWrite(dg, bytes, address);
    if (!writes && !reads) continue;
    const std::size_t ado = dg.ado();
    if (ado < ecat::kProcessRam) {
      if (!writes) continue;
      const std::size_t s = directory_.slaveFor(address);
      if (s != directory_.kNone) onSmWrite(directory_.slaves()[s].data, dg, bytes);
      continue;
    }
    std::size_t s = address.target == SlaveTarget::Station ? directory_.findStation(address.value)
                                                           : directory_.findPosition(address.value);
    // A slave the ENI gives areas for is known from its first datagram on.
    if (s == directory_.kNone && address.target == SlaveTarget::Station &&
        configuredFor(address.value) != nullptr) {
      s = directory_.slaveFor(address);
    }
    const Slave* slave = s == directory_.kNone ? nullptr : &directory_.slaves()[s];
    const std::optional<std::uint16_t> out_at = slave ? areaOf(*slave, false) : std::nullopt;
    const std::optional<std::uint16_t> in_at = slave ? areaOf(*slave, true) : std::nullopt;
    const bool has_out = out_at.has_value();
    const std::size_t out_start = out_at.value_or(0);
    const bool has_in = in_at.has_value();
    const std::size_t in_start = in_at.value_or(0);
    bool in = false;
    if (writes && has_out && out_start == ado) {
      in = false;
    } else if (reads && has_in && in_start == ado) {
      in = true;
    } else if (writes && !has_out && looksLikeMailbox(bytes, dg.data_offset, dg.data_captured)) {
      // Seen in use: the master writes a mailbox message here.
      if (s == directory_.kNone && (s = directory_.slaveFor(address)) == directory_.kNone) continue;
      directory_.slaves()[s].data.out_seen = static_cast<std::uint16_t>(ado);
      in = false;
    } else if (reads && has_out && !has_in && out_start != ado && dg.wkc == 1 &&
               looksLikeMailbox(bytes, dg.data_offset, dg.data_captured)) {
      directory_.slaves()[s].data.in_seen = static_cast<std::uint16_t>(ado);
      in = true;
    } else {
      continue;
    }
    const MailboxMessage m = decodeMailbox(bytes, dg.data_offset, dg.data_captured);
    onMailbox(directory_.slaves()[s], m, bytes, in, out);
  }
}

void MailboxTracker::onMailbox(Slave& slave, const MailboxMessage& m, const ByteReader& bytes,
                               bool in, std::vector<BusEvent>& out) {
  MbxData& data = slave.data;
  if (m.status == MailboxStatus::NotMailbox) return;
  if (m.status == MailboxStatus::LengthBeyondData) {
    if (!data.length_noted) {
      data.length_noted = true;
      note(slave, fmt::format("mailbox length {} larger than the {} bytes the datagram holds "
                              "after the header: not decoded",
                              m.length, m.available - std::min<std::size_t>(m.available, 6)));
    }
    return;
  }
  if (in) {
    // A message is read once; the counter (1..7) tells a repeat of the one read before.
    if (m.counter != 0 && data.last_counter == m.counter) {
      ++counts_.repeats;
      return;
    }
    data.last_counter = m.counter;
  }
  ++counts_.messages;
  switch (m.type) {
    case ecat::kMailboxTypeCoe:
      ++counts_.coe;
      break;
    case ecat::kMailboxTypeEoe:
      ++counts_.eoe;
      return;
    case ecat::kMailboxTypeFoe:
      ++counts_.foe;
      return;
    case ecat::kMailboxTypeSoe:
      ++counts_.soe;
      return;
    case ecat::kMailboxTypeAoe:
      ++counts_.aoe;
      return;
    case ecat::kMailboxTypeVoe:
      ++counts_.voe;
      return;
    default:
      ++counts_.other;
      return;
  }
  if (m.status == MailboxStatus::Short) {
    note(slave, fmt::format("CoE message of {} bytes too short for its service {}", m.length,
                            m.coe_service));
    return;
  }
  if (m.coe_service == ecat::kCoeServiceSdoInformation) ++counts_.sdo_information;
  if (m.emergency) {
    ++counts_.emergencies;
    DriveMessage message;
    message.kind = DriveMessage::Kind::Emergency;
    message.slave = refOf(slave);
    message.emergency = *m.emergency;
    out.push_back(BusEvent{
        now_, EmergencyEvent{message.slave, m.emergency->code, m.emergency->error_register}});
    emit(message);
    return;
  }
  if (!m.sdo) return;
  // The direction is the area's: a drive aborts with the request service too (ETG.1000.6).
  if (!in) {
    onRequest(slave, *m.sdo);
  } else if (!m.sdo->request || m.sdo->kind == SdoKind::Abort) {
    onAnswer(slave, *m.sdo, bytes, out);
  }
}

std::optional<MailboxTracker::Pending> MailboxTracker::takePending(MbxData& data,
                                                                   std::uint16_t index,
                                                                   std::uint8_t sub, bool upload) {
  for (std::size_t i = 0; i < data.pending_count; ++i) {
    const Pending p = data.pending[i];
    if (p.index != index || p.subindex != sub || p.upload != upload) continue;
    for (std::size_t k = i + 1; k < data.pending_count; ++k) data.pending[k - 1] = data.pending[k];
    --data.pending_count;
    return p;
  }
  return std::nullopt;
}

void MailboxTracker::onRequest(Slave& slave, const SdoMessage& sdo) {
  MbxData& data = slave.data;
  switch (sdo.kind) {
    case SdoKind::InitiateUpload:
    case SdoKind::InitiateDownload: {
      const bool upload = sdo.kind == SdoKind::InitiateUpload;
      // A request sent again replaces the one before; the oldest open one gives way.
      takePending(data, sdo.index, sdo.subindex, upload);
      if (data.pending_count == kMaxPending) {
        for (std::size_t k = 1; k < kMaxPending; ++k) data.pending[k - 1] = data.pending[k];
        --data.pending_count;
      }
      Pending p;
      p.index = sdo.index;
      p.subindex = sdo.subindex;
      p.upload = upload;
      p.frame = frame_;
      p.value = sdo.value;
      p.size = sdo.size.value_or(0);
      data.pending[data.pending_count++] = p;
      if (upload) data.transfer.reset();
      return;
    }
    case SdoKind::Abort:
      takePending(data, sdo.index, sdo.subindex, true);
      takePending(data, sdo.index, sdo.subindex, false);
      data.transfer.reset();
      return;
    default:
      return;  // segment requests: the answers carry what counts
  }
}

void MailboxTracker::onAnswer(Slave& slave, const SdoMessage& sdo, const ByteReader& bytes,
                              std::vector<BusEvent>& out) {
  MbxData& data = slave.data;
  ++counts_.sdo_answers;
  DriveMessage message;
  message.slave = refOf(slave);
  message.index = sdo.index;
  message.subindex = sdo.subindex;
  switch (sdo.kind) {
    case SdoKind::Abort: {
      auto p = takePending(data, sdo.index, sdo.subindex, true);
      if (!p) p = takePending(data, sdo.index, sdo.subindex, false);
      if (!p && data.transfer && data.transfer->index == sdo.index &&
          data.transfer->subindex == sdo.subindex && data.transfer->request_frame) {
        Pending from_transfer;
        from_transfer.frame = *data.transfer->request_frame;
        p = from_transfer;
      }
      data.transfer.reset();
      if (!p) ++counts_.sdo_unpaired;
      message.kind = DriveMessage::Kind::SdoAbort;
      message.abort_code = sdo.abort_code;
      if (p) message.request_frame = p->frame;
      SdoAbortEvent event{message.slave,         sdo.index, sdo.subindex, sdo.abort_code,
                          message.request_frame, false};
      event.expected = sdo.index == diag::kPredefinedErrorField && sdo.subindex >= 1 &&
                       sdo.abort_code == diag::kAbortNoDataAvailable;
      out.push_back(BusEvent{now_, event});
      emit(message);
      return;
    }
    case SdoKind::InitiateDownload: {
      auto p = takePending(data, sdo.index, sdo.subindex, false);
      if (!p) ++counts_.sdo_unpaired;
      message.kind = DriveMessage::Kind::SdoDownload;
      if (p) {
        message.request_frame = p->frame;
        message.value = p->value;
        message.size = p->size;
        // Writing 0 to 1003h:0 clears the drive's history (seed 002).
        if (sdo.index == diag::kPredefinedErrorField && sdo.subindex == 0 && p->value == 0u) {
          data.cleared = true;
          data.error_count = 0;
        }
      }
      emit(message);
      return;
    }
    case SdoKind::InitiateUpload: {
      auto p = takePending(data, sdo.index, sdo.subindex, true);
      if (!p) ++counts_.sdo_unpaired;
      message.kind = DriveMessage::Kind::SdoUpload;
      if (p) message.request_frame = p->frame;
      message.size = sdo.size.value_or(static_cast<std::uint32_t>(sdo.data_size));
      if (!sdo.expedited && sdo.size && sdo.data_size < *sdo.size) {
        // The rest comes in segments.
        if (*sdo.size > kMaxTransferBytes) {
          note(slave, fmt::format("SDO upload of 0x{:04X}:{} declares {} bytes: not followed",
                                  sdo.index, sdo.subindex, *sdo.size));
          return;
        }
        Transfer t;
        t.index = sdo.index;
        t.subindex = sdo.subindex;
        t.request_frame = message.request_frame;
        t.size = sdo.size;
        t.received = static_cast<std::uint32_t>(sdo.data_size);
        for (std::size_t k = 0; k < std::min<std::size_t>(sdo.data_size, 8); ++k) {
          t.first[k] = bytes.u8(sdo.data_at + k).value_or(0);
        }
        data.transfer = t;
        return;
      }
      message.value = sdo.value;
      onUploaded(slave, message, out);
      return;
    }
    case SdoKind::UploadSegment:
      onSegment(slave, sdo, bytes, out);
      return;
    default:
      return;
  }
}

// An upload segment: joined to the transfer it continues, its toggle and length checked.
void MailboxTracker::onSegment(Slave& slave, const SdoMessage& sdo, const ByteReader& bytes,
                               std::vector<BusEvent>& out) {
  MbxData& data = slave.data;
  DriveMessage message;
  message.slave = refOf(slave);
  if (!data.transfer) {
    ++counts_.sdo_unpaired;
    return;
  }
  Transfer& t = *data.transfer;
  if (sdo.toggle != t.toggle) {
    note(slave, fmt::format("SDO upload of 0x{:04X}:{}: segment toggle {} where {} was due: "
                            "transfer dropped",
                            t.index, t.subindex, sdo.toggle ? 1 : 0, t.toggle ? 1 : 0));
    data.transfer.reset();
    return;
  }
  t.toggle = !t.toggle;
  for (std::size_t k = t.received; k < 8 && k - t.received < sdo.data_size; ++k) {
    t.first[k] = bytes.u8(sdo.data_at + (k - t.received)).value_or(0);
  }
  const std::uint64_t received = std::uint64_t{t.received} + sdo.data_size;
  const std::uint64_t bound = t.size ? *t.size : kMaxTransferBytes;
  if (received > bound) {
    note(slave, fmt::format("SDO upload of 0x{:04X}:{} runs past its {} bytes: transfer "
                            "dropped",
                            t.index, t.subindex, bound));
    data.transfer.reset();
    return;
  }
  t.received = static_cast<std::uint32_t>(received);
  if (!sdo.last) return;
  message.kind = DriveMessage::Kind::SdoUpload;
  message.index = t.index;
  message.subindex = t.subindex;
  message.request_frame = t.request_frame;
  message.size = t.received;
  if (t.received <= 8) message.value = firstBytes(t.first, t.received);
  data.transfer.reset();
  onUploaded(slave, message, out);
  return;
}

// An upload complete: 1003h:0 read lower than before with no clear in between (ERH-001).
void MailboxTracker::onUploaded(Slave& slave, DriveMessage& message, std::vector<BusEvent>& out) {
  MbxData& data = slave.data;
  if (message.index == diag::kPredefinedErrorField && message.subindex == 0 && message.value) {
    const auto now = static_cast<std::uint32_t>(*message.value & 0xFF);
    if (data.error_count && now < *data.error_count && !data.cleared) {
      out.push_back(BusEvent{now_, ErrorHistoryShrunkEvent{message.slave, *data.error_count, now,
                                                           data.error_count_at.frame}});
    }
    data.error_count = now;
    data.error_count_at = now_;
    data.cleared = false;
  }
  emit(message);
}

void MailboxTracker::emit(DriveMessage message) {
  message.frame = frame_;
  message.time_ns = time_ns_;
  frame_messages_.push_back(message);
  if (messages_.size() < kMaxMessages) {
    messages_.push_back(std::move(message));
  } else {
    ++omitted_;
  }
}

void MailboxTracker::note(const Slave& slave, std::string text) {
  if (notes_.size() >= kMaxNotes) {
    ++notes_omitted_;
    return;
  }
  notes_.push_back(MailboxNote{frame_, refOf(slave), std::move(text)});
}

}  // namespace ncservo
