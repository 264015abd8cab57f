// Where each axis's PDOs sit in a frame (docs/protocol.md §9), and which copy of the frame it is
// (docs/protocol.md §8). One decoder follows one capture in order; its memory is bounded.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "ncservo/base/byte_reader.hpp"
#include "ncservo/layout/axis_config.hpp"
#include "ncservo/layout/layout_learner.hpp"
#include "ncservo/protocol/pdo_layout.hpp"
#include "ncservo/wire/ethercat.hpp"

namespace ncservo {

enum class LayoutSource : std::uint8_t { None, Inferred, Startup, Config, Eni };
const char* layoutSourceName(LayoutSource source);

enum class CopyKind : std::uint8_t { Master, Returned };
const char* copyKindName(CopyKind copy);

struct AxisInfo {
  std::uint16_t index = 0;
  std::string name;
  bool logical = true;        // exchanged with logical commands, else with FPRD/FPWR
  std::uint32_t outputs = 0;  // logical addresses of the RxPDO and TxPDO (when logical)
  std::uint32_t inputs = 0;
  std::uint16_t sm_outputs = 0;  // the station's SM2 and SM3 physical addresses (when not)
  std::uint16_t sm_inputs = 0;
  std::uint16_t station = 0;
  bool has_station = false;  // station known: the axis's AL state can be followed
};

// Where one axis's PDOs sit in one frame. Offsets are into the bytes given to the walker.
struct AxisPlacement {
  std::uint16_t axis = 0;
  bool rx_placed = false;  // the datagrams of this frame hold the axis's RxPDO region
  bool tx_placed = false;  // ... and its TxPDO region (valid or not)
  bool has_rx = false;
  bool has_tx = false;        // inputs present and valid: returned copy, WKC above zero
  bool rx_malformed = false;  // the RxPDO region is cut short or straddles the datagram's end
  bool tx_malformed = false;
  std::uint16_t rx_datagram = 0;  // index in EcatFrame::datagrams
  std::uint16_t tx_datagram = 0;
  std::size_t rx_offset = 0;
  std::size_t tx_offset = 0;
};

inline constexpr std::size_t kMaxAxesPerFrame = 208;  // 2047 data bytes / 10-byte RxPDO, rounded up

struct FrameDecode {
  CopyKind copy = CopyKind::Master;
  bool paired = false;         // a returned copy whose master's copy was the frame just before
  bool registers = false;      // some datagram reaches slave registers (a start-up's do)
  bool any_malformed = false;  // some placed region is cut short or straddles its datagram
  // Non-zero when the placements came from (or went into) the shape cache: frames with the same
  // id have the same datagram list (commands, lengths, surviving addresses), copy and placements.
  std::uint64_t shape_id = 0;
  std::size_t axis_count = 0;
  std::array<AxisPlacement, kMaxAxesPerFrame> axes{};  // in axis order
};

// The placed PDO regions a capture cut short (a snap length): in how many frames, the first, and
// of which axes. One flag per axis: bounded.
class CutRegions {
 public:
  // One placement of a frame; only a cut region counts.
  void add(std::uint64_t frame, const AxisPlacement& placement);
  void add(std::uint64_t frame, const FrameDecode& decode) {
    for (std::size_t i = 0; i < decode.axis_count; ++i) add(frame, decode.axes[i]);
  }
  std::uint64_t frames() const { return frames_; }
  std::uint64_t firstFrame() const { return first_frame_; }
  // The axes with a region cut in some frame, in axis order.
  std::vector<std::uint16_t> axes() const;

 private:
  std::uint64_t frames_ = 0;
  std::uint64_t first_frame_ = 0;
  std::uint64_t last_frame_ = 0;
  std::vector<bool> axes_;
};

// An axis as a configuration file would give it (for `decode --layout`).
AxisConfig axisConfigOf(const AxisInfo& info);

// How a --config file gives an axis (docs/configuration.md#axis), for the text a person reads
// beside a reason that asks for one; several lines, so never inside a one-line reason.
inline constexpr const char* kLayoutConfigExample =
    "[[axis]]\nname = \"X\"\noutputs = 0x00010000  # its 10-byte RxPDO\ninputs = 0x00010028   "
    "# its 40-byte TxPDO\n";

struct DecoderOptions {
  // Explicit layout (a configuration, an ENI, or inferred by a LayoutWindow); empty = none.
  std::vector<AxisConfig> axes;
  LayoutSource explicit_source = LayoutSource::Config;  // where `axes` came from
  // The layout may be inferred from the cyclic traffic (docs/protocol.md §9.4, by a LayoutWindow).
  bool default_layout = true;
  // Why the inference refused to decide (for noServoReason); empty when it did not run.
  std::string inference_refusal;
  // The slaves' mailbox areas an ENI gave (docs/drive-messages.md): used where the capture holds
  // no start-up writing the sync managers.
  std::vector<MailboxArea> mailbox_areas;
};

class Decoder {
 public:
  explicit Decoder(DecoderOptions options);

  // Places each axis's PDOs in one walked frame and tells its copy (any status; only complete
  // datagram headers are used). `bytes` are the bytes the frame was walked over.
  void placeAxes(const EcatFrame& frame, const ByteReader& bytes, FrameDecode& out);

  LayoutSource source() const;
  const std::vector<AxisInfo>& axes() const { return axes_; }
  // The axis whose slave has this station address (configuration, ENI or start-up), if any: the
  // one place a slave's message or finding is given its axis (docs/drive-messages.md).
  std::optional<std::uint16_t> axisOfStation(std::uint16_t station) const;
  // A start-up configured slaves' sync managers and none is a servo of this protocol.
  bool startupShowsNoServo() const { return learner_.sawConfiguration() && !learner_.sawServo(); }
  // What the start-up showed of every slave (learned whatever the layout source).
  const LayoutLearner& learner() const { return learner_; }
  // Why no axis was found, for a person, one line (empty while axes are known).
  std::string noServoReason() const;
  // No axis was found, and a --config file would give them (layoutConfigExample shows one).
  bool noServoWantsLayout() const { return axes_.empty() && !startupShowsNoServo(); }
  // The mailbox areas an ENI gave (DecoderOptions::mailbox_areas).
  const std::vector<MailboxArea>& mailboxAreas() const { return options_.mailbox_areas; }

 private:
  // `signature`: of the datagram list; `any_wkc`: some WKC is above zero.
  void classifyCopy(const EcatFrame& frame, std::uint64_t signature, bool any_wkc,
                    FrameDecode& out);
  bool fromCache(std::uint64_t key, FrameDecode& out) const;
  void toCache(std::uint64_t key, FrameDecode& out);
  void setAxes(const std::vector<AxisConfig>& axes);
  const std::vector<AxisConfig>& placedAxes() const {
    return options_.axes.empty() ? learned_axes_ : options_.axes;
  }
  void placeConfigured(const EcatFrame& frame, FrameDecode& out);
  AxisPlacement* placementFor(FrameDecode& out, std::uint16_t axis);
  void placeRegion(const Datagram& dg, std::uint16_t dg_index, std::size_t start, Pdo pdo,
                   bool returned, FrameDecode& out, std::uint16_t axis);

  DecoderOptions options_;
  std::vector<AxisInfo> axes_;
  std::uint64_t previous_signature_ = 0;
  bool previous_was_master_ = false;
  // The start-up's SM/FMMU configuration (docs/protocol.md §9.3), and the axes it gave so far.
  LayoutLearner learner_;
  std::uint32_t learned_generation_ = 0;
  std::vector<AxisConfig> learned_axes_;

  // Placements of recently seen frame shapes (same datagram list, framing, copy and WKCs): a
  // cyclic frame is placed once, not every cycle. Any change to the layout state invalidates it.
  static constexpr std::size_t kCachedAxes = 32;
  struct CachedPlacements {
    bool valid = false;
    std::uint64_t key = 0;
    std::uint64_t generation = 0;
    CopyKind copy = CopyKind::Master;
    bool any_malformed = false;
    std::uint64_t shape_id = 0;
    std::size_t axis_count = 0;
    std::array<AxisPlacement, kCachedAxes> axes{};
  };
  std::array<CachedPlacements, 4> cache_{};
  std::size_t cache_next_ = 0;
  std::uint64_t generation_ = 0;
  std::uint64_t last_shape_id_ = 0;
};

}  // namespace ncservo
