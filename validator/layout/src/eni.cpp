// ENI import (ETG.2100 EtherCATConfig.xml) through pugixml. Paths used (root
// EtherCATConfig/Config):
//   Slave/Info/{Name, PhysAddr, AutoIncAddr}
//   Slave/ProcessData/Send|Recv/{BitStart, BitLength}     outputs | inputs, in image bits
//   Slave/ProcessData/Sm2|Sm3/DefaultSize                   the sync managers' sizes, bytes
//   Slave/Mailbox/Send|Recv/Start                           SM0 | SM1, the mailbox areas
//   Cyclic/CycleTime                                        each task's cycle, µs
//   Cyclic/Frame/Cmd/{Cmd, Addr, DataLength, OutputOffs, InputOffs, Cnt}
// Every <Cyclic> element is read: a second task has one of its own.
// A slave's logical address: for the LRD/LWR/LRW whose image range holds its first byte,
// Addr + floor(BitStart / 8) - OutputOffs (outputs) or - InputOffs (inputs).
#include "ncservo/layout/eni.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <limits>
#include <pugixml.hpp>
#include <sstream>

#include "ncservo/base/number.hpp"
#include "ncservo/protocol/pdo_layout.hpp"
#include "ncservo/wire/ethercat.hpp"

namespace ncservo {
namespace {

// ETG.2000 HexDecValue: "#x1A00" or "0x1A00" is hexadecimal, anything else decimal (may be
// negative, e.g. AutoIncAddr -1).
std::optional<std::int64_t> hexDec(std::string_view text) {
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.front())))
    text.remove_prefix(1);
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back())))
    text.remove_suffix(1);
  int base = 10;
  if (text.size() > 2 && (text.substr(0, 2) == "#x" || text.substr(0, 2) == "0x" ||
                          text.substr(0, 2) == "#X" || text.substr(0, 2) == "0X")) {
    base = 16;
    text.remove_prefix(2);
  }
  const Result<std::int64_t> value = parseNumber<std::int64_t>(text, base);
  if (!value) return std::nullopt;
  return *value;
}

Error eniError(const std::string& path, std::uint64_t line, std::string message) {
  return Error{path, line, 0, {}, std::move(message)};
}

struct Command {
  std::uint8_t cmd = 0;
  std::uint32_t address = 0;
  std::int64_t length = 0;
  std::optional<std::int64_t> output_offset;
  std::optional<std::int64_t> input_offset;
};

class Reader {
 public:
  Reader(std::string path, std::string_view xml) : path_(std::move(path)), xml_(xml) {}

  std::uint32_t lineOf(const pugi::xml_node& node) const { return lineAt(node.offset_debug()); }
  std::uint32_t lineAt(std::ptrdiff_t offset) const {
    if (offset < 0) return 0;
    const auto end = std::min<std::size_t>(static_cast<std::size_t>(offset), xml_.size());
    return static_cast<std::uint32_t>(
        std::count(xml_.begin(), xml_.begin() + static_cast<std::ptrdiff_t>(end), '\n') + 1);
  }
  Error error(const pugi::xml_node& node, std::string message) const {
    return eniError(path_, node ? lineOf(node) : 0, std::move(message));
  }
  // The number in child `name` of `node`. A missing one (when required) or one that is no number
  // records an error; the first one recorded is kept.
  std::optional<std::int64_t> number(const pugi::xml_node& node, const char* name, bool required) {
    const pugi::xml_node child = node.child(name);
    if (!child) {
      if (required) record(error(node, fmt::format("<{}> has no <{}>", node.name(), name)));
      return std::nullopt;
    }
    auto value = hexDec(child.child_value());
    if (!value) {
      record(error(child, fmt::format("<{}> is not a number: '{}'", name, child.child_value())));
    }
    return value;
  }
  bool failed() const { return first_error_.has_value(); }
  const Error& firstError() const { return *first_error_; }

 private:
  void record(Error error) {
    if (!first_error_) first_error_ = std::move(error);
  }

  std::string path_;
  std::string_view xml_;
  std::optional<Error> first_error_;
};

// The cyclic commands of every task: each task's frames kept in `layout`, and the logical
// commands returned, which place the slaves' process data.
Result<std::vector<Command>> readCyclicCommands(const pugi::xml_node& config, Reader& reader,
                                                EniLayout& layout) {
  std::vector<Command> commands;
  for (pugi::xml_node cyclic : config.children("Cyclic")) {
    const std::optional<std::int64_t> cycle_us = reader.number(cyclic, "CycleTime", false);
    if (reader.failed()) return fail(reader.firstError());
    for (pugi::xml_node frame : cyclic.children("Frame")) {
      EniCyclicFrame& kept = layout.frames.emplace_back();
      if (cycle_us && *cycle_us > 0 && *cycle_us <= std::numeric_limits<std::uint32_t>::max()) {
        kept.cycle_us = static_cast<std::uint32_t>(*cycle_us);
      }
      for (pugi::xml_node cmd : frame.children("Cmd")) {
        auto code = reader.number(cmd, "Cmd", true);
        if (reader.failed()) return fail(reader.firstError());
        if (!ecat::isLogical(static_cast<std::uint8_t>(*code))) continue;
        Command c;
        c.cmd = static_cast<std::uint8_t>(*code);
        auto addr = reader.number(cmd, "Addr", true);
        auto length = reader.number(cmd, "DataLength", true);
        c.output_offset = reader.number(cmd, "OutputOffs", false);
        c.input_offset = reader.number(cmd, "InputOffs", false);
        if (reader.failed()) return fail(reader.firstError());
        c.address = static_cast<std::uint32_t>(*addr);
        c.length = *length;
        commands.push_back(c);
        kept.commands.push_back(
            {c.cmd, c.address, static_cast<std::uint32_t>(std::max<std::int64_t>(0, c.length))});
      }
    }
  }
  return commands;
}

// The logical address of image byte `byte`, through the command whose range holds it.
std::optional<std::uint32_t> logicalAddress(const std::vector<Command>& commands, std::int64_t byte,
                                            bool outputs) {
  for (const Command& c : commands) {
    const bool carries = outputs ? ecat::writesSlaves(c.cmd) : ecat::readsSlaves(c.cmd);
    const auto& offset = outputs ? c.output_offset : c.input_offset;
    if (!carries || !offset || byte < *offset || byte >= *offset + c.length) continue;
    return static_cast<std::uint32_t>(c.address + (byte - *offset));
  }
  return std::nullopt;
}

// A slave's process data in one direction (<Send> outputs, <Recv> inputs): where it starts in the
// image and how many bits it holds, summed over its entries.
struct ImageBits {
  std::optional<std::int64_t> start;
  std::int64_t bits = 0;
};
Result<ImageBits> imageBits(const pugi::xml_node& process_data, const char* direction,
                            Reader& reader) {
  ImageBits image;
  for (pugi::xml_node entry : process_data.children(direction)) {
    auto start = reader.number(entry, "BitStart", true);
    auto bits = reader.number(entry, "BitLength", true);
    if (reader.failed()) return fail(reader.firstError());
    if (!image.start) image.start = start;
    image.bits += *bits;
  }
  return image;
}

// The slave's axis when its process data is a servo's (10-byte outputs, 40-byte inputs);
// nullopt when it is another slave.
Result<std::optional<AxisConfig>> servoAxis(const pugi::xml_node& slave, Reader& reader,
                                            const std::vector<Command>& commands,
                                            std::size_t axes_before) {
  const pugi::xml_node info = slave.child("Info");
  const std::string name = info.child("Name").child_value();
  auto station = reader.number(info, "PhysAddr", false);
  if (reader.failed()) return fail(reader.firstError());
  // Sizes of the process data: the Send/Recv bit lengths, or the sync managers' sizes.
  const pugi::xml_node pd = slave.child("ProcessData");
  const Result<ImageBits> send = imageBits(pd, "Send", reader);
  if (!send) return fail(send.error());
  const Result<ImageBits> recv = imageBits(pd, "Recv", reader);
  if (!recv) return fail(recv.error());
  const bool servo = send->bits == 8 * static_cast<std::int64_t>(kRxPdoSize) &&
                     recv->bits == 8 * static_cast<std::int64_t>(kTxPdoSize);
  if (!servo) return std::nullopt;
  if (*send->start % 8 != 0 || *recv->start % 8 != 0) {
    return fail(reader.error(
        pd, fmt::format("slave '{}': its process data does not start on a byte", name)));
  }
  AxisConfig axis;
  axis.name = name.empty() ? fmt::format("axis{}", axes_before) : name;
  auto outputs = logicalAddress(commands, *send->start / 8, true);
  auto inputs = logicalAddress(commands, *recv->start / 8, false);
  if (!outputs || !inputs) {
    return fail(reader.error(pd, fmt::format("slave '{}': its {} (image bit {}) are in no "
                                             "cyclic LRD/LWR/LRW command of <Cyclic>",
                                             name, outputs ? "inputs" : "outputs",
                                             outputs ? *recv->start : *send->start)));
  }
  axis.outputs = *outputs;
  axis.inputs = *inputs;
  if (station) axis.station = static_cast<std::uint16_t>(*station);
  return axis;
}

}  // namespace

// The slave's mailbox areas, when it has a station address and a <Mailbox> with both starts.
std::optional<MailboxArea> mailboxArea(const pugi::xml_node& slave, Reader& reader) {
  const pugi::xml_node mailbox = slave.child("Mailbox");
  if (!mailbox) return std::nullopt;
  const auto station = reader.number(slave.child("Info"), "PhysAddr", false);
  const auto out = reader.number(mailbox.child("Send"), "Start", false);
  const auto in = reader.number(mailbox.child("Recv"), "Start", false);
  constexpr std::int64_t kMax = 0xFFFF;
  const auto fits = [](const std::optional<std::int64_t>& v) { return v && *v >= 0 && *v <= kMax; };
  if (!fits(station) || !fits(out) || !fits(in)) return std::nullopt;
  return MailboxArea{static_cast<std::uint16_t>(*station), static_cast<std::uint16_t>(*out),
                     static_cast<std::uint16_t>(*in)};
}

Result<EniLayout> parseEni(std::string_view xml, const std::string& path) {
  EniLayout layout;
  Reader reader(path, xml);
  pugi::xml_document doc;
  const pugi::xml_parse_result parsed = doc.load_buffer(xml.data(), xml.size());
  if (!parsed) {
    return fail(eniError(path, reader.lineAt(parsed.offset),
                         fmt::format("not well-formed XML: {}", parsed.description())));
  }
  const pugi::xml_node config = doc.child("EtherCATConfig").child("Config");
  if (!config) {
    return fail(eniError(path, 0, "no <EtherCATConfig><Config>: not an ENI file (ETG.2100)"));
  }
  const Result<std::vector<Command>> commands = readCyclicCommands(config, reader, layout);
  if (!commands) return fail(commands.error());
  for (pugi::xml_node slave : config.children("Slave")) {
    ++layout.slaves;
    Result<std::optional<AxisConfig>> axis =
        servoAxis(slave, reader, *commands, layout.axes.size());
    if (!axis) return fail(axis.error());
    if (*axis) layout.axes.push_back(std::move(**axis));
    if (const std::optional<MailboxArea> area = mailboxArea(slave, reader)) {
      layout.mailboxes.push_back(*area);
    }
    if (reader.failed()) return fail(reader.firstError());
  }
  return layout;
}

Result<EniLayout> loadEni(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return fail(eniError(path, 0, "cannot open the ENI file"));
  std::ostringstream text;
  text << in.rdbuf();
  return parseEni(text.str(), path);
}

}  // namespace ncservo
