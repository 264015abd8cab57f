// Writing an ENI file (EtherCATConfig.xml, ETG.2100) for a simulated set-up, in the form
// parseEni (ncservo/eni.hpp) reads.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace ncservo::sim {

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
  // Its mailbox (Mailbox/Send|Recv/Start: SM0 and SM1), when it has one; 0: none.
  std::uint16_t mailbox_out = 0;
  std::uint16_t mailbox_in = 0;
  std::uint16_t mailbox_bytes = 0;
};
struct EniCyclicCommand {
  std::uint8_t command = 0;   // LRW, LWR or LRD
  std::uint32_t address = 0;  // logical address
  std::uint16_t length = 0;
  std::uint16_t expected_wkc = 0;
  std::size_t frame = 0;       // the cyclic frame that carries it; the commands in frame order
  std::uint32_t cycle_us = 0;  // of the task that sends that frame
};
// One <Cyclic> element per task (the frames of one cycle time, in a row), each with its
// <CycleTime>.
std::string writeEni(const std::vector<EniSlave>& slaves,
                     const std::vector<EniCyclicCommand>& commands);

}  // namespace ncservo::sim
