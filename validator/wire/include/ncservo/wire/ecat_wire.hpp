// EtherCAT wire facts (docs/protocol.md §8, ETG.1000.4, ETG.1000.6): frame and datagram layout,
// commands, ESC registers and their fields, AL states, the CoE mailbox and the PDO objects, and
// the carriers an EtherCAT frame travels in. Facts only; what reads them lives elsewhere
// (ethercat.hpp walks frames).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace ncservo::ecat {

// --- Carriers: Ethernet II, 802.1Q/802.1ad tags, IPv4/IPv6 UDP, capture link types ---
inline constexpr std::uint16_t kEtherType = 0x88A4;
inline constexpr std::uint16_t kUdpPort = 34980;
inline constexpr std::size_t kEthernetHeaderSize = 14;         // destination, source, EtherType
inline constexpr std::size_t kEthernetMinFrame = 60;           // without the FCS
inline constexpr std::uint8_t kMacLocallyAdministered = 0x02;  // in the first byte of a MAC
inline constexpr std::uint16_t kEtherTypeVlan = 0x8100;
inline constexpr std::uint16_t kEtherTypeQinQ = 0x88A8;
inline constexpr std::uint16_t kEtherTypeQinQOld = 0x9100;
inline constexpr std::uint16_t kEtherTypeIpv4 = 0x0800;
inline constexpr std::uint16_t kEtherTypeIpv6 = 0x86DD;
inline constexpr std::size_t kVlanTagSize = 4;  // TCI, then the next EtherType
inline constexpr std::uint8_t kIpProtoUdp = 17;
inline constexpr std::size_t kIpv4MinHeaderSize = 20;
inline constexpr std::size_t kIpv6HeaderSize = 40;
inline constexpr std::size_t kUdpHeaderSize = 8;
inline constexpr std::size_t kSllHeaderSize = 16;   // Linux cooked v1, protocol type last
inline constexpr std::size_t kSll2HeaderSize = 20;  // Linux cooked v2, protocol type first
inline constexpr int kDltEthernet = 1;              // tcpdump.org link types
inline constexpr int kDltLinuxSll = 113;
inline constexpr int kDltLinuxSll2 = 276;
// The carriers above as a libpcap capture filter (live capture, docs/field.md): EtherCAT in
// Ethernet or in UDP, also behind VLAN tags.
inline constexpr const char* kCaptureFilter =
    "ether proto 0x88a4 or udp port 34980 or (vlan and (ether proto 0x88a4 or udp port 34980))";
static_assert(kEtherType == 0x88A4 && kUdpPort == 34980, "kCaptureFilter spells them out");

// --- Frame header (2 bytes): chain length in bits 10..0, type in bits 15..12 ---
inline constexpr std::size_t kFrameHeaderSize = 2;
inline constexpr std::uint16_t kLengthMask = 0x07FF;
inline constexpr unsigned kFrameTypeShift = 12;
inline constexpr std::uint16_t kFrameTypeDatagrams = 1;

// --- Datagram: header, data, working counter ---
inline constexpr std::size_t kDatagramCommandAt = 0;     // 1 byte
inline constexpr std::size_t kDatagramIndexAt = 1;       // 1 byte
inline constexpr std::size_t kDatagramAddressAt = 2;     // 4 bytes: ADP/ADO or logical address
inline constexpr std::size_t kDatagramLengthWordAt = 6;  // 2 bytes: length and the flags below
inline constexpr std::size_t kDatagramIrqAt = 8;         // 2 bytes
inline constexpr std::size_t kDatagramHeaderSize = 10;
static_assert(kDatagramIrqAt + 2 == kDatagramHeaderSize);
inline constexpr std::uint16_t kCirculatingBit = 0x4000;
inline constexpr std::uint16_t kMoreBit = 0x8000;
inline constexpr std::size_t kWkcSize = 2;
// The frame header's 11-bit length bounds a chain: at most this many minimal datagrams.
inline constexpr std::size_t kMaxDatagrams =
    (kLengthMask + kDatagramHeaderSize + kWkcSize) / (kDatagramHeaderSize + kWkcSize) + 1;

enum Command : std::uint8_t {
  kNop = 0,
  kAprd = 1,
  kApwr = 2,
  kAprw = 3,
  kFprd = 4,
  kFpwr = 5,
  kFprw = 6,
  kBrd = 7,
  kBwr = 8,
  kBrw = 9,
  kLrd = 10,
  kLwr = 11,
  kLrw = 12,
  kArmw = 13,
  kFrmw = 14,
};

// How a command addresses slaves: ADP/ADO with ADP = −ring position (auto-increment), ADP =
// configured station address, every slave (broadcast), or a 32-bit logical address.
enum class Addressing : std::uint8_t { None, AutoIncrement, Configured, Broadcast, Logical };

// Whether the addressed slaves' memory is read into the datagram and written from it.
// ARMW/FRMW read one slave and write the others: counted as reads of the addressed one.
struct CommandFacts {
  const char* name;
  Addressing addressing;
  bool reads;
  bool writes;
};
inline constexpr std::array<CommandFacts, 15> kCommands{{
    {.name = "NOP", .addressing = Addressing::None, .reads = false, .writes = false},
    {.name = "APRD", .addressing = Addressing::AutoIncrement, .reads = true, .writes = false},
    {.name = "APWR", .addressing = Addressing::AutoIncrement, .reads = false, .writes = true},
    {.name = "APRW", .addressing = Addressing::AutoIncrement, .reads = true, .writes = true},
    {.name = "FPRD", .addressing = Addressing::Configured, .reads = true, .writes = false},
    {.name = "FPWR", .addressing = Addressing::Configured, .reads = false, .writes = true},
    {.name = "FPRW", .addressing = Addressing::Configured, .reads = true, .writes = true},
    {.name = "BRD", .addressing = Addressing::Broadcast, .reads = true, .writes = false},
    {.name = "BWR", .addressing = Addressing::Broadcast, .reads = false, .writes = true},
    {.name = "BRW", .addressing = Addressing::Broadcast, .reads = true, .writes = true},
    {.name = "LRD", .addressing = Addressing::Logical, .reads = true, .writes = false},
    {.name = "LWR", .addressing = Addressing::Logical, .reads = false, .writes = true},
    {.name = "LRW", .addressing = Addressing::Logical, .reads = true, .writes = true},
    {.name = "ARMW", .addressing = Addressing::AutoIncrement, .reads = true, .writes = false},
    {.name = "FRMW", .addressing = Addressing::Configured, .reads = true, .writes = false},
}};
static_assert(kCommands.size() == kFrmw + 1, "one row per command, indexed by its code");

// --- ESC registers ---
inline constexpr std::uint16_t kRegType = 0x0000;
inline constexpr std::uint16_t kRegStationAddress = 0x0010;
inline constexpr std::uint16_t kRegStationAlias = 0x0012;
inline constexpr std::uint16_t kRegAlControl = 0x0120;
inline constexpr std::uint16_t kRegAlStatus = 0x0130;
inline constexpr std::uint16_t kRegAlStatusCode = 0x0134;
inline constexpr std::uint16_t kRegFmmu0 = 0x0600;
inline constexpr std::uint16_t kFmmuStride = 16;
inline constexpr std::size_t kFmmuCount = 16;
inline constexpr std::uint16_t kRegSyncManager0 = 0x0800;
inline constexpr std::uint16_t kSyncManagerStride = 8;
inline constexpr std::size_t kSyncManagerCount = 16;
inline constexpr std::uint16_t kRegDcSystemTime = 0x0910;        // 64 bits (or 32), ns
inline constexpr std::uint16_t kRegDcSystemTimeOffset = 0x0920;  // 64 bits: local to system time
// 32 bits, sign and magnitude: bit 31 set when the local copy of the system time is smaller
// than the system time received; bits 30..0 the difference in ns (ESC datasheet, DC registers).
inline constexpr std::uint16_t kRegDcSystemTimeDifference = 0x092C;
inline constexpr std::uint32_t kDcDifferenceSignBit = 0x80000000u;
// ESC error counters (ETG.1000.4, ESC datasheets): 0x0300 + 2n invalid frames and 0x0301 + 2n RX
// errors at port n, 0x0308 + n forwarded RX errors, 0x030C processing unit, 0x030D PDI errors,
// 0x0310 + n lost links. Each saturates at 0xFF; a write to 0x0300-0x030B clears them.
inline constexpr std::uint16_t kRegErrorCounters = 0x0300;
inline constexpr std::size_t kErrorCountersSize = 0x14;
inline constexpr std::size_t kEscPorts = 4;
inline constexpr std::uint16_t kRegInvalidFrame0 = 0x0300;  // + 2n
inline constexpr std::uint16_t kRegRxError0 = 0x0301;       // + 2n
inline constexpr std::uint16_t kRegForwardedRxError0 = 0x0308;
inline constexpr std::uint16_t kRegProcessingUnitError = 0x030C;
inline constexpr std::uint16_t kRegPdiError = 0x030D;
inline constexpr std::uint16_t kRegLostLink0 = 0x0310;
inline constexpr std::uint16_t kRegErrorCountersClearedEnd = 0x030C;  // writes below clear
// Sync manager watchdog: status (bit 0 clear: expired) and the SM and PDI watchdog counters.
inline constexpr std::uint16_t kRegSmWatchdogStatus = 0x0440;
inline constexpr std::uint16_t kRegSmWatchdogCounter = 0x0442;
inline constexpr std::uint16_t kRegPdiWatchdogCounter = 0x0443;
inline constexpr std::size_t kWatchdogCountersSize = 2;  // 0x0442-0x0443, cleared by a write
// Process RAM starts here: FPRD/FPWR at or above it exchange process data, not registers.
inline constexpr std::uint16_t kProcessRam = 0x1000;
static_assert(kRegFmmu0 + kFmmuCount * kFmmuStride <= kRegSyncManager0);
static_assert(kRegSyncManager0 + kSyncManagerCount * kSyncManagerStride <= kRegDcSystemTime);

// Fields of one sync manager: byte offsets in its 8 bytes.
inline constexpr std::size_t kSmStartAt = 0;   // 2 bytes, physical start address
inline constexpr std::size_t kSmLengthAt = 2;  // 2 bytes
inline constexpr std::size_t kSmControlAt = 4;
inline constexpr std::size_t kSmStatusAt = 5;
inline constexpr std::size_t kSmActivateAt = 6;  // bit 0: enabled
inline constexpr std::size_t kSmPdiControlAt = 7;
static_assert(kSmPdiControlAt + 1 == kSyncManagerStride);
inline constexpr std::uint8_t kSmModeMask = 0x03;  // in the control byte
inline constexpr std::uint8_t kSmModeMailbox = 0x02;
// Sync managers by convention (ETG.1000.4, docs/protocol.md §8).
inline constexpr std::size_t kMailboxOutSm = 0;  // master to slave
inline constexpr std::size_t kMailboxInSm = 1;   // slave to master
inline constexpr std::size_t kOutputsSm = 2;     // RxPDO
inline constexpr std::size_t kInputsSm = 3;      // TxPDO

// Fields of one FMMU: byte offsets in its 16 bytes.
inline constexpr std::size_t kFmmuLogicalAt = 0;  // 4 bytes
inline constexpr std::size_t kFmmuLengthAt = 4;   // 2 bytes
inline constexpr std::size_t kFmmuStartBitAt = 6;
inline constexpr std::size_t kFmmuStopBitAt = 7;
inline constexpr std::size_t kFmmuPhysicalAt = 8;  // 2 bytes
inline constexpr std::size_t kFmmuPhysicalStartBitAt = 10;
inline constexpr std::size_t kFmmuTypeAt = 11;
inline constexpr std::size_t kFmmuActivateAt = 12;  // bit 0: active
static_assert(kFmmuActivateAt < kFmmuStride);
inline constexpr std::uint8_t kFmmuRead = 1;   // type: the slave's inputs
inline constexpr std::uint8_t kFmmuWrite = 2;  // type: the slave's outputs

// --- AL states, in bits 3..0 of AL control and AL status ---
enum AlState : std::uint8_t {
  kAlInit = 1,
  kAlPreOp = 2,
  kAlBoot = 3,
  kAlSafeOp = 4,
  kAlOp = 8,
};
inline constexpr std::array<std::uint8_t, 5> kAlStates{kAlInit, kAlPreOp, kAlBoot, kAlSafeOp,
                                                       kAlOp};
inline constexpr std::uint8_t kAlStateMask = 0x0F;
// The AL states in which a slave exchanges inputs (docs/protocol.md §8).
inline constexpr bool exchangesInputs(std::uint8_t al_state) {
  return al_state == kAlOp || al_state == kAlSafeOp;
}
// Error indicator in AL status, error acknowledge in AL control.
inline constexpr std::uint8_t kAlErrorBit = 0x10;
// AL status codes (ETG.1000.6).
inline constexpr std::uint16_t kAlCodeInvalidTransition = 0x0011;
inline constexpr std::uint16_t kAlCodeSyncError = 0x001A;
inline constexpr std::uint16_t kAlCodeInvalidOutputs = 0x001D;
inline constexpr std::uint16_t kAlCodeEepromNoAccess = 0x0050;

// --- Mailbox and CoE SDO (ETG.1000.4 mailbox, ETG.1000.6 CoE) ---
// Mailbox header: length 2 (of what follows the header), address 2, channel/priority 1,
// type 1 (low 4 bits) and counter.
inline constexpr std::size_t kMailboxLengthAt = 0;
inline constexpr std::size_t kMailboxAddressAt = 2;
inline constexpr std::size_t kMailboxChannelAt = 4;  // channel bits 5..0, priority bits 7..6
inline constexpr std::size_t kMailboxTypeAt = 5;
inline constexpr std::size_t kMailboxHeaderSize = 6;
inline constexpr std::uint8_t kMailboxChannelMask = 0x3F;
inline constexpr unsigned kMailboxPriorityShift = 6;
inline constexpr std::uint8_t kMailboxTypeMask = 0x0F;
inline constexpr unsigned kMailboxCounterShift = 4;  // in the type byte, bits 6..4
inline constexpr std::uint8_t kMailboxCounterMask = 0x07;
inline constexpr std::uint8_t kMailboxTypeError = 0;
inline constexpr std::uint8_t kMailboxTypeAoe = 1;
inline constexpr std::uint8_t kMailboxTypeEoe = 2;
inline constexpr std::uint8_t kMailboxTypeCoe = 3;
inline constexpr std::uint8_t kMailboxTypeFoe = 4;
inline constexpr std::uint8_t kMailboxTypeSoe = 5;
inline constexpr std::uint8_t kMailboxTypeVoe = 15;
// CoE header: number in bits 8..0, service in bits 15..12.
inline constexpr std::size_t kCoeHeaderSize = 2;
inline constexpr std::uint16_t kCoeNumberMask = 0x01FF;
inline constexpr unsigned kCoeServiceShift = 12;
inline constexpr std::uint8_t kCoeServiceEmergency = 1;
inline constexpr std::uint8_t kCoeServiceSdoRequest = 2;
inline constexpr std::uint8_t kCoeServiceSdoResponse = 3;
inline constexpr std::uint8_t kCoeServiceSdoInformation = 8;
// Emergency, after the CoE header: error code 2, error register 1 (as 1001h), manufacturer data 5.
inline constexpr std::size_t kEmcyCodeAt = 0;
inline constexpr std::size_t kEmcyRegisterAt = 2;
inline constexpr std::size_t kEmcyDataAt = 3;
inline constexpr std::size_t kEmcyDataSize = 5;
inline constexpr std::size_t kEmcySize = kEmcyDataAt + kEmcyDataSize;
// SDO: command 1, index 2, subindex 1, then 4 bytes of data (expedited) or of size (normal).
inline constexpr std::size_t kSdoCommandAt = 0;
inline constexpr std::size_t kSdoIndexAt = 1;
inline constexpr std::size_t kSdoSubindexAt = 3;
inline constexpr std::size_t kSdoDataAt = 4;
inline constexpr std::size_t kSdoDataSize = 4;
inline constexpr unsigned kSdoSpecifierShift = 5;  // command specifier in bits 7..5
// Client (request) command specifiers.
inline constexpr std::uint8_t kSdoDownloadSegmentRequest = 0;
inline constexpr std::uint8_t kSdoInitiateDownloadRequest = 1;
inline constexpr std::uint8_t kSdoInitiateUploadRequest = 2;
inline constexpr std::uint8_t kSdoUploadSegmentRequest = 3;
inline constexpr std::uint8_t kSdoAbort = 4;  // either way
// Server (response) command specifiers.
inline constexpr std::uint8_t kSdoUploadSegmentResponse = 0;
inline constexpr std::uint8_t kSdoDownloadSegmentResponse = 1;
inline constexpr std::uint8_t kSdoInitiateUploadResponse = 2;
inline constexpr std::uint8_t kSdoInitiateDownloadResponse = 3;
// A segment: the command byte (toggle bit 4; of the data, bits 3..1 the unused bytes of 7 and
// bit 0 "last segment"), then its data: 7 bytes, or all that the mailbox length gives beyond.
inline constexpr std::uint8_t kSdoToggle = 0x10;
inline constexpr std::uint8_t kSdoLastSegment = 0x01;
inline constexpr unsigned kSdoSegmentUnusedShift = 1;
inline constexpr std::uint8_t kSdoSegmentUnusedMask = 0x07;
inline constexpr std::size_t kSdoSegmentDataAt = 1;
inline constexpr std::size_t kSdoSegmentMinData = 7;
inline constexpr std::uint8_t kSdoSizeIndicated = 0x01;
inline constexpr std::uint8_t kSdoExpedited = 0x02;
inline constexpr unsigned kSdoUnusedBytesShift = 2;  // of an expedited transfer, bits 3..2
inline constexpr std::uint8_t kSdoUnusedBytesMask = 0x03;
inline constexpr std::uint8_t kSdoCompleteAccess = 0x10;

// --- CoE objects that size the process data ---
inline constexpr std::uint16_t kRxPdoAssignment = 0x1C12;  // PDOs assigned to SM2 (outputs)
inline constexpr std::uint16_t kTxPdoAssignment = 0x1C13;  // PDOs assigned to SM3 (inputs)
inline constexpr std::uint16_t kRxPdoMappingFirst = 0x1600;
inline constexpr std::uint16_t kRxPdoMappingLast = 0x17FF;
inline constexpr std::uint16_t kTxPdoMappingFirst = 0x1A00;
inline constexpr std::uint16_t kTxPdoMappingLast = 0x1BFF;
inline constexpr std::uint32_t kPdoEntryBitsMask = 0xFF;  // low byte of a mapping entry

}  // namespace ncservo::ecat
