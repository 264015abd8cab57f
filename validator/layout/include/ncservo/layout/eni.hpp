// Reading the servos' layout from an ENI file (EtherCATConfig.xml, ETG.2100), the layout source
// of docs/protocol.md §9.2.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ncservo/base/error.hpp"
#include "ncservo/layout/axis_config.hpp"

namespace ncservo {

// A cyclic command of the ENI (<Cyclic>/<Frame>/<Cmd>).
struct EniCommand {
  std::uint8_t command = 0;  // its EtherCAT command code
  std::uint32_t address = 0;
  std::uint32_t length = 0;
};
// A cyclic frame of the ENI, with the cycle time of the task it belongs to: each <Cyclic> element
// is one task with its own <CycleTime> (µs) and frames.
struct EniCyclicFrame {
  std::optional<std::uint32_t> cycle_us;  // none: its <Cyclic> gives no <CycleTime>
  std::vector<EniCommand> commands;
};

// One axis per servo of this protocol (10-byte RxPDO, 40-byte TxPDO), in the file's slave order,
// with its logical addresses and its station address; and the cyclic frames of every task.
struct EniLayout {
  std::vector<AxisConfig> axes;
  std::size_t slaves = 0;  // slaves in the file, servos or not
  std::vector<EniCyclicFrame> frames;
  // Every slave's (servo or not) with a station address and both mailbox starts.
  std::vector<MailboxArea> mailboxes;
};

// An error names the file and, when it is about one element, its line: "FILE:LINE: MESSAGE".
Result<EniLayout> parseEni(std::string_view xml, const std::string& path);
Result<EniLayout> loadEni(const std::string& path);

}  // namespace ncservo
