// Reading the servos' layout from an ENI file (EtherCATConfig.xml, ETG.2100), the layout source
// of PROTOCOL.md §9.2, and writing one for a simulated set-up.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ncservo/config.hpp"
#include "ncservo/error.hpp"

namespace ncservo {

// One axis per servo of this protocol (10-byte RxPDO, 40-byte TxPDO), in the file's slave order,
// with its logical addresses and its station address.
struct EniLayout {
  std::vector<AxisConfig> axes;
  std::size_t slaves = 0;  // slaves in the file, servos or not
};

// An error names the file and, when it is about one element, its line: "FILE:LINE: MESSAGE".
Result<EniLayout> parseEni(std::string_view xml, const std::string& path);
Result<EniLayout> loadEni(const std::string& path);

// An ENI for a set-up: each slave's name, station, auto-increment address, its outputs and inputs
// (logical address and size in bytes; 0 when it has none) and the cyclic commands that carry them.
struct EniSlave {
  std::string name;
  std::uint16_t station = 0;
  std::uint16_t position = 0;
  std::uint32_t outputs = 0;
  std::uint16_t output_bytes = 0;
  std::uint32_t inputs = 0;
  std::uint16_t input_bytes = 0;
};
struct EniCyclicCommand {
  std::uint32_t address = 0;  // logical address of the LRW
  std::uint16_t length = 0;
  std::uint16_t expected_wkc = 0;
};
std::string writeEni(const std::vector<EniSlave>& slaves,
                     const std::vector<EniCyclicCommand>& commands, std::uint32_t cycle_us);

}  // namespace ncservo
