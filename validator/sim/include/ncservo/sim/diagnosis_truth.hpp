// The truth of `ncservo simulate --diagnosis` (docs/simulate.md#diagnosis): what the drives and
// the ESCs said on the wire, as `validate` must list it.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace ncservo::sim {

// What the drives and the ESCs said on the wire with --diagnosis (docs/simulate.md#diagnosis), as
// `validate` must list it (docs/drive-messages.md), each on the returned frame of the read that
// carried it (counted from 1 in the capture).
struct DriveSaid {
  std::uint64_t frame = 0;
  std::uint16_t station = 0;
  const char* kind = "";  // emergency, sdo-upload, sdo-download or sdo-abort
  std::optional<std::uint64_t> request_frame;
  std::uint16_t index = 0;
  std::uint8_t subindex = 0;
  std::optional<std::uint64_t> value;
  std::uint16_t code = 0;  // an emergency's
  std::uint8_t error_register = 0;
  std::uint32_t abort_code = 0;
};
struct EscErrorTruth {  // a counter's rise since the slave's last read (the first is the baseline)
  std::uint64_t frame = 0;
  std::uint16_t station = 0;
  std::uint8_t port = 0;
  const char* counter = "";  // diag::escCounterName
  std::uint32_t delta = 0;
};
struct LinkFaultTruth {  // the bad link into a slave's port, and the frames it corrupted
  std::uint64_t frame = 0;
  std::uint16_t station = 0;
  std::uint8_t port = 0;
  std::uint32_t errors = 0;
};
struct DiagnosisTruth {
  std::vector<DriveSaid> drive_messages;
  std::vector<EscErrorTruth> esc_errors;
  std::vector<LinkFaultTruth> link_faults;
};
// `{"drive_messages": [...], "esc_errors": [...], "link_faults": [...]}` with validate's JSON
// names, for --diagnosis-truth.
std::string diagnosisJson(const DiagnosisTruth& truth);

}  // namespace ncservo::sim
