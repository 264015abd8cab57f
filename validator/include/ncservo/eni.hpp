// Reading the servos' layout from an ENI file (EtherCATConfig.xml, ETG.2100), the layout source
// of PROTOCOL.md §9.2.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ncservo/config.hpp"

namespace ncservo {

struct EniError {
  std::string path;
  std::uint32_t line = 0;  // 0 when the error is about the file as a whole
  std::string message;
  std::string text() const;  // "FILE:LINE: MESSAGE"
};

struct EniResult {
  // One axis per servo of this protocol (10-byte RxPDO, 40-byte TxPDO), in the file's slave order,
  // with its logical addresses and its station address.
  std::vector<AxisConfig> axes;
  std::size_t slaves = 0;  // slaves in the file, servos or not
  std::optional<EniError> error;
  bool ok() const { return !error.has_value(); }
};

EniResult parseEni(std::string_view xml, const std::string& path);
EniResult loadEni(const std::string& path);

}  // namespace ncservo
