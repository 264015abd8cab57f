#include "ncservo/sim/eni_writer.hpp"

#include <fmt/format.h>

#include <optional>
#include <pugixml.hpp>
#include <sstream>

#include "ncservo/wire/ethercat.hpp"

namespace ncservo::sim {

std::string writeEni(const std::vector<EniSlave>& slaves,
                     const std::vector<EniCyclicCommand>& commands) {
  // Image offsets: each command's data at its own place in the process image, as a frame's
  // first datagram would sit (after the Ethernet, EtherCAT and datagram headers), one region per
  // command.
  constexpr std::uint32_t kFirstOffset =
      ecat::kEthernetHeaderSize + ecat::kFrameHeaderSize + ecat::kDatagramHeaderSize;
  constexpr std::uint32_t kRegion = 2048;
  auto offsetOf = [&](std::uint32_t address, std::size_t& which) -> std::optional<std::uint32_t> {
    for (std::size_t i = 0; i < commands.size(); ++i) {
      const EniCyclicCommand& c = commands[i];
      if (address >= c.address && address < c.address + c.length) {
        which = i;
        return kFirstOffset + static_cast<std::uint32_t>(i) * kRegion + (address - c.address);
      }
    }
    return std::nullopt;
  };
  auto hex = [](std::uint64_t value, int digits) {
    return fmt::format("#x{:0{}x}", value, digits);
  };

  pugi::xml_document doc;
  pugi::xml_node decl = doc.append_child(pugi::node_declaration);
  decl.append_attribute("version") = "1.0";
  decl.append_attribute("encoding") = "UTF-8";
  pugi::xml_node config = doc.append_child("EtherCATConfig").append_child("Config");
  pugi::xml_node master = config.append_child("Master").append_child("Info");
  master.append_child("Name").text().set("ncservo simulate");
  for (const EniSlave& s : slaves) {
    pugi::xml_node slave = config.append_child("Slave");
    pugi::xml_node info = slave.append_child("Info");
    info.append_child("Name").text().set(s.name.c_str());
    info.append_child("PhysAddr").text().set(s.station);
    info.append_child("AutoIncAddr").text().set(static_cast<int>(-static_cast<int>(s.position)));
    if (s.mailbox_bytes > 0) {
      pugi::xml_node mailbox = slave.append_child("Mailbox");
      for (const auto& [name, start] : {std::pair{"Send", s.mailbox_out}, {"Recv", s.mailbox_in}}) {
        pugi::xml_node area = mailbox.append_child(name);
        area.append_child("Start").text().set(start);
        area.append_child("Length").text().set(s.mailbox_bytes);
      }
    }
    pugi::xml_node pd = slave.append_child("ProcessData");
    std::size_t which = 0;
    if (s.output_bytes > 0) {
      if (auto offset = offsetOf(s.outputs, which)) {
        pugi::xml_node send = pd.append_child("Send");
        send.append_child("BitStart").text().set(*offset * 8);
        send.append_child("BitLength").text().set(s.output_bytes * 8);
      }
    }
    if (s.input_bytes > 0) {
      if (auto offset = offsetOf(s.inputs, which)) {
        pugi::xml_node recv = pd.append_child("Recv");
        recv.append_child("BitStart").text().set(*offset * 8);
        recv.append_child("BitLength").text().set(s.input_bytes * 8);
      }
    }
  }
  pugi::xml_node cyclic;
  pugi::xml_node frame;
  for (std::size_t i = 0; i < commands.size(); ++i) {
    const EniCyclicCommand& c = commands[i];
    const bool new_task = i == 0 || c.cycle_us != commands[i - 1].cycle_us;
    if (new_task) {
      cyclic = config.append_child("Cyclic");
      cyclic.append_child("CycleTime").text().set(c.cycle_us);
    }
    if (new_task || c.frame != commands[i - 1].frame) frame = cyclic.append_child("Frame");
    pugi::xml_node cmd = frame.append_child("Cmd");
    cmd.append_child("State").text().set("SAFEOP");
    cmd.append_child("State").text().set("OP");
    cmd.append_child("Cmd").text().set(static_cast<int>(c.command));
    cmd.append_child("Addr").text().set(hex(c.address, 8).c_str());
    cmd.append_child("DataLength").text().set(c.length);
    cmd.append_child("Cnt").text().set(c.expected_wkc);
    const std::uint32_t offset = kFirstOffset + static_cast<std::uint32_t>(i) * kRegion;
    if (ecat::readsSlaves(c.command)) cmd.append_child("InputOffs").text().set(offset);
    if (ecat::writesSlaves(c.command)) cmd.append_child("OutputOffs").text().set(offset);
  }
  std::ostringstream out;
  doc.save(out, "  ");
  return out.str();
}

}  // namespace ncservo::sim
