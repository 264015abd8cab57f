// One axis's place in the process image, as a configuration file, an ENI or the start-up gives it
// (docs/layout.md).
#pragma once

#include <cstdint>
#include <optional>
#include <string>

namespace ncservo {

// A slave's mailbox areas as a configuration tool set them (the ENI's Slave/Mailbox/Send and
// Recv starts): SM0, where the master writes its requests, and SM1, where it reads the answers
// (docs/drive-messages.md).
struct MailboxArea {
  std::uint16_t station = 0;
  std::uint16_t out_start = 0;
  std::uint16_t in_start = 0;
};

struct AxisConfig {
  std::string name;
  // Logical addresses of the 10-byte RxPDO and the 40-byte TxPDO (LRW/LRD/LWR exchange) ...
  std::optional<std::uint32_t> outputs;
  std::optional<std::uint32_t> inputs;
  // ... or a configured station address and SM2/SM3 physical addresses (FPRD/FPWR exchange).
  std::optional<std::uint16_t> station;
  std::optional<std::uint16_t> sm_outputs;
  std::optional<std::uint16_t> sm_inputs;
  std::optional<int> servo_ready_mode;

  // Exchanged with FPRD/FPWR at SM addresses; else logical. A logical axis may still name its
  // station, which ties it to that slave's AL state (ESM-002).
  bool physical() const { return sm_outputs.has_value() || sm_inputs.has_value(); }
};

}  // namespace ncservo
