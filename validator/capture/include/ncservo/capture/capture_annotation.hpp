// A copy of a capture with packet comments (pcapng opt_comment, §3.5) on chosen frames, so that
// stock Wireshark shows them (frame.comment) without the plugin.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ncservo/base/error.hpp"

namespace ncservo {

// Packet comments by 1-based frame number (as Wireshark numbers frames).
using FrameComments = std::map<std::uint64_t, std::vector<std::string>>;
// Which frames a copy keeps, by number and capture time; null keeps every frame.
using FrameFilter = std::function<bool(std::uint64_t frame, std::int64_t time_ns)>;
// Which comments a copy replaces (an earlier annotation's own); null replaces none.
using CommentFilter = std::function<bool(std::string_view comment)>;

// Copies the capture file `input` (read again from its start) to the pcapng `output`, with each
// kept frame's comments added after the comments it has, less those `replaced` picks (on every
// frame: annotating again replaces its own comments). A pcapng's blocks are copied as stored,
// every block that is no packet (interfaces, statistics, name resolution, other sections) kept;
// a pcap becomes a pcapng with the same frames, link type, timestamps and resolution. A
// compressed pcapng cannot be copied block by block and is refused.
Status annotateCapture(const std::string& input, const std::string& output,
                       const FrameComments& comments, const FrameFilter& keep,
                       const CommentFilter& replaced = nullptr);

// A stored pcapng packet block (Enhanced or obsolete Packet Block, either byte order) with
// `comments` added after its options, its comments that `replaced` picks left out; nullopt for a
// block that cannot hold options (a Simple Packet Block) or that is malformed.
std::optional<std::vector<std::uint8_t>> withComments(const std::uint8_t* block, std::size_t size,
                                                      const std::vector<std::string>& comments,
                                                      const CommentFilter& replaced = nullptr);

}  // namespace ncservo
