// libFuzzer target: a slave's mailbox traffic and error-counter reads (PROTOCOL.md §11) through the
// mailbox decoder and the trackers (mailbox.hpp, mailbox_tracker.hpp, esc_errors.hpp), on frames
// walked as the validator walks them. Input: a sequence of chunks, each a control byte (bit 0: the
// slave's answer in SM1, else the master's write to SM0; bit 1: a counter read of 0x0300; bit 2:
// WKC 0; bits 5..3: the slave, of eight), a length byte, then that many bytes of datagram data.
// The first frame configures every slave's SM0 and SM1 as mailboxes, so the chunks reach the
// decoder; its state (pending requests, transfers) must stay bounded over any sequence.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "ncservo/model/esc_errors.hpp"
#include "ncservo/model/mailbox_tracker.hpp"
#include "ncservo/wire/ethercat.hpp"
#include "ncservo/wire/mailbox.hpp"

namespace {

using ncservo::ecat::Command;
constexpr std::uint16_t kOut = 0x1000;
constexpr std::uint16_t kIn = 0x1080;

// An Ethernet frame with one datagram (no padding: ASan sees a read past its data).
std::vector<std::uint8_t> frameOf(std::uint8_t command, std::uint16_t adp, std::uint16_t ado,
                                  const std::uint8_t* data, std::size_t size, std::uint16_t wkc) {
  std::vector<std::uint8_t> f = {1, 1, 5, 1, 0, 0, 2, 0, 0, 0, 0, 1, 0x88, 0xA4};
  const std::size_t chain = 10 + size + 2;
  f.push_back(static_cast<std::uint8_t>(chain & 0xFF));
  f.push_back(static_cast<std::uint8_t>(0x10 | ((chain >> 8) & 0x07)));
  f.insert(f.end(),
           {command, 0, static_cast<std::uint8_t>(adp), static_cast<std::uint8_t>(adp >> 8),
            static_cast<std::uint8_t>(ado), static_cast<std::uint8_t>(ado >> 8),
            static_cast<std::uint8_t>(size), static_cast<std::uint8_t>(size >> 8), 0, 0});
  f.insert(f.end(), data, data + size);
  f.push_back(static_cast<std::uint8_t>(wkc));
  f.push_back(static_cast<std::uint8_t>(wkc >> 8));
  return f;
}

struct Run {
  ncservo::MailboxTracker mailbox;
  ncservo::EscErrorTracker esc;
  ncservo::FrameAddressing addressing;
  std::vector<ncservo::BusEvent> events;
  ncservo::EcatFrame frame;
  std::uint64_t number = 0;

  void feed(const std::vector<std::uint8_t>& bytes, bool returned) {
    const ncservo::ByteReader reader(bytes.data(), bytes.size());
    ncservo::walkPacket(ncservo::LinkType::Ethernet, reader, frame);
    if (frame.status != ncservo::WalkStatus::Ok && frame.status != ncservo::WalkStatus::Truncated)
      return;
    addressing.beginFrame(frame, returned, false);
    ++number;
    const ncservo::Stamp now{number, static_cast<std::int64_t>(number) * 1000};
    events.clear();
    mailbox.onFrame(frame, reader, addressing, now, now.time_ns, events);
    esc.onFrame(frame, reader, addressing, now, events);
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static Run* run = nullptr;
  delete run;
  run = new Run;
  // SM0 (0x1000, 128 bytes, mailbox write) and SM1 (0x1080, 128 bytes, mailbox read).
  const std::uint8_t sms[16] = {0x00, 0x10, 0x80, 0, 0x26, 0, 1, 0,
                                0x80, 0x10, 0x80, 0, 0x22, 0, 1, 0};
  for (std::uint16_t slave = 0; slave < 8; ++slave) {
    run->feed(frameOf(Command::kFpwr, 0x1001 + slave, 0x0800, sms, sizeof sms, 0), false);
  }
  std::size_t at = 0;
  std::size_t seen = 0;
  while (at + 2 <= size) {
    const std::uint8_t control = data[at];
    const std::size_t length = std::min<std::size_t>(data[at + 1], size - at - 2);
    const std::uint8_t* body = data + at + 2;
    at += 2 + length;
    const auto station = static_cast<std::uint16_t>(0x1001 + ((control >> 3) & 7));
    const std::uint16_t wkc = (control & 4) != 0 ? 0 : 1;
    // The decoder alone, on exactly the chunk's bytes.
    const ncservo::MailboxMessage m =
        ncservo::decodeMailbox(ncservo::ByteReader(body, length), 0, length);
    seen += m.length + (m.sdo ? m.sdo->data_size : 0);
    if ((control & 2) != 0) {
      run->feed(frameOf(Command::kFprd, station, 0x0300, body, length, wkc), true);
    } else if ((control & 1) != 0) {
      run->feed(frameOf(Command::kFprd, station, kIn, body, length, wkc), true);
    } else {
      run->feed(frameOf(Command::kFpwr, station, kOut, body, length, 0), false);
    }
  }
  for (const ncservo::DriveMessage& message : run->mailbox.messages()) seen += message.size;
  for (const ncservo::MailboxNote& note : run->mailbox.notes()) seen += note.text.size();
  for (const ncservo::LinkFault& fault : run->esc.linkFaults())
    seen += ncservo::linkFaultText(fault).size();
  return seen == 0xFFFFFFFF ? 1 : 0;
}
