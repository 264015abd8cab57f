// The PDO assignment and mapping a start-up reads or writes over CoE (ETG.1000.6): SDO requests
// in the mailbox the master writes (SM0) and SDO responses in the mailbox it reads back (SM1).
// Only the objects that size the process data are kept: 0x1C12/0x1C13 (PDOs assigned to SM2/SM3)
// and 0x1600-0x17FF/0x1A00-0x1BFF (the entries of each PDO, low byte = bit length). Bounded.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "ncservo/base/byte_reader.hpp"

namespace ncservo {

class CoePdoObjects {
 public:
  static constexpr std::size_t kMaxEntries = 512;

  // One mailbox as captured (a write to SM0: `request`, or a read of SM1). Only CoE SDO
  // download requests and upload responses (expedited, normal or complete access) are taken.
  void onMailbox(const ByteReader& bytes, std::size_t offset, std::size_t length, bool request);

  // Bits of process data the assignment object (0x1C12 outputs, 0x1C13 inputs) gives, once it
  // and every PDO it names are known.
  std::optional<std::uint32_t> assignedBits(std::uint16_t assignment) const;
  bool empty() const { return entries_.empty(); }
  void absorb(const CoePdoObjects& other);

 private:
  struct Entry {
    std::uint16_t index;
    std::uint8_t sub;
    std::uint32_t value;
  };
  void store(std::uint16_t index, std::uint8_t sub, std::uint32_t value);
  // Complete access from `sub` (0 or 1): sub 0 is one byte padded to two, then the entries.
  void storeComplete(std::uint16_t index, std::uint8_t sub, const ByteReader& bytes, std::size_t at,
                     std::size_t size);
  std::optional<std::uint32_t> value(std::uint16_t index, std::uint8_t sub) const;
  std::vector<Entry> entries_;
};

}  // namespace ncservo
