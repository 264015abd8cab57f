// Learning where each servo's PDOs are from the capture's own start-up (docs/protocol.md §9.3): the
// sync manager (0x0800 + 8n) and FMMU (0x0600 + 16n) registers the master writes, per slave. A
// slave whose SM2 is 10 bytes and SM3 40 bytes is a servo of this protocol; its FMMUs give the
// logical addresses of its RxPDO and TxPDO, or, with no FMMU over them, it is exchanged with
// FPRD/FPWR at the SM physical addresses. Bounded memory; one pass.
#pragma once

#include <array>
#include <bitset>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "ncservo/base/byte_reader.hpp"
#include "ncservo/layout/axis_config.hpp"
#include "ncservo/wire/coe_pdo.hpp"
#include "ncservo/wire/ethercat.hpp"
#include "ncservo/wire/slave_directory.hpp"

namespace ncservo {

// A slave's SM and FMMU registers as far as the capture showed them (byte by byte).
struct SlaveRegisters {
  std::array<std::uint8_t, ecat::kFmmuCount * ecat::kFmmuStride> fmmu{};
  std::bitset<ecat::kFmmuCount * ecat::kFmmuStride> fmmu_known;
  std::array<std::uint8_t, ecat::kSyncManagerCount * ecat::kSyncManagerStride> sm{};
  std::bitset<ecat::kSyncManagerCount * ecat::kSyncManagerStride> sm_known;
  bool physical_exchange = false;  // FPRD/FPWR seen at a configured servo's SM addresses
  CoePdoObjects coe;               // the PDO assignment and mapping read or written over CoE
  void absorb(const SlaveRegisters& other);
};

struct SyncManagerView {
  std::size_t index = 0;
  std::uint16_t start = 0;
  std::uint16_t length = 0;
  std::uint8_t control = 0;
  bool enabled = false;
};
struct FmmuView {
  std::size_t index = 0;
  std::uint32_t logical = 0;
  std::uint16_t length = 0;
  std::uint16_t physical = 0;
  std::uint8_t type = 0;  // 1 read (inputs), 2 write (outputs), 3 both
  bool active = false;
};
struct SlaveLayout {
  std::optional<std::uint16_t> station;
  std::optional<std::uint16_t> position;
  std::vector<SyncManagerView> sync_managers;  // those whose start and length are known
  std::vector<FmmuView> fmmus;                 // those whose logical start, length, type are known
  // Process data sizes the CoE PDO assignment gives (0x1C12 outputs, 0x1C13 inputs), in bits.
  std::optional<std::uint32_t> coe_output_bits;
  std::optional<std::uint32_t> coe_input_bits;
  // SM2 10 bytes and SM3 40 bytes, or (SM lengths not written) a CoE assignment of 80/320 bits.
  bool servo = false;
};

class LayoutLearner {
 public:
  // Every frame in capture order (see AlTracker::onFrame for `returned` and `paired`). Writes are
  // taken from master copies, and from returned copies whose master copy was not captured.
  void onFrame(const EcatFrame& frame, const ByteReader& bytes, bool returned, bool paired);

  // Whether any slave's sync managers have the sizes of a servo of this protocol.
  bool sawServo() const { return saw_servo_; }
  // The servos found so far, in ring order, with station and logical (or SM) addresses.
  const std::vector<AxisConfig>& axes() const { return axes_; }
  // Changes whenever axes() does.
  std::uint32_t generation() const { return generation_; }
  // Whether the capture gave any slave's sync manager a non-zero length (a start-up was captured).
  bool sawConfiguration() const { return saw_configuration_; }
  // Every slave seen, with its registers, in ring order (for `decode --layout` and tests).
  std::vector<SlaveLayout> slaves() const;
  // Frames addressing slaves' registers (not only logical process data) that the capture's snap
  // length cut short: what the start-up wrote after the cut is unknown, so a slave configured
  // there may be missing from axes().
  std::uint64_t configurationFramesCut() const { return configuration_frames_cut_; }

 private:
  // A mailbox write to SM `sm` (0) or read of it (1) of the addressed slave; whether it was one.
  bool observeMailbox(const Datagram& dg, const ByteReader& bytes, const SlaveAddress& address,
                      std::size_t sm);
  // Copies the SM/FMMU bytes the datagram carries; whether anything changed.
  bool touch(SlaveRegisters& regs, const Datagram& dg, const ByteReader& bytes);
  void rebuild();

  SlaveDirectory<SlaveRegisters> directory_;
  std::vector<AxisConfig> axes_;
  std::uint32_t generation_ = 0;
  bool saw_configuration_ = false;
  bool saw_servo_ = false;
  bool dirty_ = false;
  std::uint64_t configuration_frames_cut_ = 0;
};

// One line for a person: "3 station 0x03EC; SM2 0x1100+10 control 0x64; FMMU0 ... write; servo".
std::string describeSlaveLayout(const SlaveLayout& slave);

// What a slave's registers say (helpers of slaves(), public for tests).
SlaveLayout describeSlave(const SlaveRegisters& regs, std::optional<std::uint16_t> station,
                          std::optional<std::uint16_t> position);

}  // namespace ncservo
