#include "ncservo/layout/decoder.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "ncservo/protocol/pdo_layout.hpp"

namespace ncservo {

namespace {
// What the decoder needs to know of a frame's datagram list, gathered in one pass.
struct FrameShape {
  // Commands, indexes, lengths and the addresses that survive the ring: what pairs a master's
  // copy with its returned copy (docs/protocol.md §8).
  std::uint64_t signature = 0;
  // Framing, commands, surviving addresses, lengths and which WKCs are above zero: what the
  // placements depend on (not the index a master changes every cycle).
  std::uint64_t layout_key = 0;
  bool any_wkc = false;    // some WKC is above zero
  bool complete = true;    // every datagram wholly captured, WKC included
  bool registers = false;  // some datagram reaches slave registers (a start-up's do)
};

FrameShape shapeOf(const EcatFrame& frame) {
  FrameShape shape;
  std::uint64_t hash = 1469598103934665603ull;
  auto mix = [&hash](std::uint64_t v) {  // one multiply-xorshift round per value (splitmix64)
    hash = (hash ^ v) * 0x9E3779B97F4A7C15ull;
    hash ^= hash >> 31;
  };
  std::uint64_t key = (std::uint64_t{frame.ecat_offset} << 48) ^ frame.count;
  mix(frame.count);
  for (std::size_t i = 0; i < frame.count; ++i) {
    const Datagram& dg = frame.datagrams[i];
    const bool survives = ecat::addressSurvivesRing(dg.command);
    mix(dg.command | (std::uint64_t{dg.index} << 8) | (std::uint64_t{dg.length} << 16));
    if (survives) mix(dg.address);
    shape.any_wkc = shape.any_wkc || (dg.has_wkc && dg.wkc > 0);
    shape.complete = shape.complete && dg.complete();
    shape.registers = shape.registers || (dg.command != ecat::kNop && dg.command != ecat::kFrmw &&
                                          !ecat::isLogical(dg.command));
    const std::uint64_t address = survives ? dg.address : 0;
    key = (key ^ (address | std::uint64_t{dg.command} << 32 | std::uint64_t{dg.length} << 40 |
                  std::uint64_t{dg.wkc > 0} << 56)) *
          0x9E3779B97F4A7C15ull;
    key ^= key >> 29;
  }
  shape.signature = hash;
  shape.layout_key = key;
  return shape;
}

// Position of [start, start+size) relative to [base, base+length): inside, partly, or outside.
enum class Overlap { None, Partial, Inside };
Overlap overlap(std::uint64_t base, std::uint64_t length, std::uint64_t start, std::uint64_t size) {
  if (start + size <= base || start >= base + length) return Overlap::None;
  if (start >= base && start + size <= base + length) return Overlap::Inside;
  return Overlap::Partial;
}
}  // namespace

const char* layoutSourceName(LayoutSource source) {
  switch (source) {
    case LayoutSource::None:
      return "none";
    case LayoutSource::Inferred:
      return "inferred";
    case LayoutSource::Startup:
      return "startup";
    case LayoutSource::Config:
      return "config";
    case LayoutSource::Eni:
      return "eni";
  }
  return "none";
}

std::optional<std::uint16_t> Decoder::axisOfStation(std::uint16_t station) const {
  std::optional<std::uint16_t> axis;
  for (const AxisInfo& info : axes_) {
    if (info.has_station && info.station == station) axis = info.index;
  }
  return axis;
}

const char* copyKindName(CopyKind copy) {
  return copy == CopyKind::Master ? "master" : "returned";
}

AxisConfig axisConfigOf(const AxisInfo& info) {
  AxisConfig axis;
  axis.name = info.name;
  if (info.has_station) axis.station = info.station;
  if (info.logical) {
    axis.outputs = info.outputs;
    axis.inputs = info.inputs;
  } else {
    axis.sm_outputs = info.sm_outputs;
    axis.sm_inputs = info.sm_inputs;
  }
  return axis;
}

Decoder::Decoder(DecoderOptions options) : options_(std::move(options)) {
  setAxes(options_.axes);
}

void Decoder::setAxes(const std::vector<AxisConfig>& axes) {
  axes_.clear();
  for (std::size_t i = 0; i < axes.size(); ++i) {
    const AxisConfig& axis = axes[i];
    AxisInfo info;
    info.index = static_cast<std::uint16_t>(i);
    info.name = axis.name.empty() ? fmt::format("axis{}", i) : axis.name;
    info.logical = !axis.physical();
    info.has_station = axis.station.has_value();
    info.outputs = axis.outputs.value_or(0);
    info.inputs = axis.inputs.value_or(0);
    info.sm_outputs = axis.sm_outputs.value_or(0);
    info.sm_inputs = axis.sm_inputs.value_or(0);
    info.station = axis.station.value_or(0);
    axes_.push_back(std::move(info));
  }
}

std::string Decoder::noServoReason() const {
  if (!axes_.empty()) return {};
  if (startupShowsNoServo()) {
    return "no servo of this protocol found: the start-up configures slaves, none with 10/40-byte "
           "sync managers (docs/layout.md)";
  }
  if (!options_.default_layout) {
    return "no servo of this protocol found: inferring the layout from the cyclic traffic is off; "
           "give the layout in a --config file";
  }
  if (!options_.inference_refusal.empty()) {
    return "no servo of this protocol found in the cyclic traffic (docs/layout.md): " +
           options_.inference_refusal;
  }
  return "no servo of this protocol found (docs/layout.md); give the layout in a --config file";
}

void CutRegions::add(std::uint64_t frame, const AxisPlacement& placement) {
  if (!placement.rx_malformed && !placement.tx_malformed) return;
  if (frames_ == 0 || frame != last_frame_) {
    if (frames_++ == 0) first_frame_ = frame;
    last_frame_ = frame;
  }
  if (placement.axis >= axes_.size()) axes_.resize(placement.axis + 1u);
  axes_[placement.axis] = true;
}

std::vector<std::uint16_t> CutRegions::axes() const {
  std::vector<std::uint16_t> out;
  for (std::size_t i = 0; i < axes_.size(); ++i) {
    if (axes_[i]) out.push_back(static_cast<std::uint16_t>(i));
  }
  return out;
}

LayoutSource Decoder::source() const {
  if (!options_.axes.empty()) return options_.explicit_source;
  if (!learned_axes_.empty()) return LayoutSource::Startup;
  return LayoutSource::None;
}

void Decoder::placeAxes(const EcatFrame& frame, const ByteReader& bytes, FrameDecode& out) {
  out.axis_count = 0;
  out.any_malformed = false;
  out.shape_id = 0;
  const FrameShape shape = shapeOf(frame);
  out.registers = shape.registers;
  classifyCopy(frame, shape.signature, shape.any_wkc, out);
  if (frame.status != WalkStatus::Ok && frame.status != WalkStatus::Truncated) return;
  // Only register commands configure slaves (the cyclic LRW and the DC FRMW are not looked
  // at); the learner follows them whatever the layout source, and its axes are used when no
  // configuration or ENI gives any.
  if (shape.registers) {
    learner_.onFrame(frame, bytes, out.copy == CopyKind::Returned, out.paired);
    if (learner_.generation() != learned_generation_) {
      learned_generation_ = learner_.generation();
      ++generation_;  // placements cached before are stale
      if (options_.axes.empty()) {
        learned_axes_ = learner_.axes();
        setAxes(learned_axes_);
      }
    }
  }
  // Only wholly captured frames are cached: their placements depend on nothing else than their
  // shape — framing, commands, addresses, lengths, which WKCs are above zero — and the copy.
  const bool cacheable = frame.status == WalkStatus::Ok && shape.complete;
  const std::uint64_t key = shape.layout_key ^ (out.copy == CopyKind::Returned ? 0x5bd1e995ull : 0);
  if (cacheable && fromCache(key, out)) return;
  const std::uint64_t generation = generation_;
  if (!placedAxes().empty()) placeConfigured(frame, out);
  const auto end = out.axes.begin() + static_cast<std::ptrdiff_t>(out.axis_count);
  const auto by_axis = [](const AxisPlacement& a, const AxisPlacement& b) {
    return a.axis < b.axis;
  };
  if (!std::is_sorted(out.axes.begin(), end, by_axis)) std::sort(out.axes.begin(), end, by_axis);
  out.any_malformed = std::any_of(out.axes.begin(), end, [](const AxisPlacement& p) {
    return p.rx_malformed || p.tx_malformed;
  });
  // A frame that changed the layout state (a new or candidate key) is placed again next time.
  if (cacheable && generation == generation_) toCache(key, out);
}

bool Decoder::fromCache(std::uint64_t key, FrameDecode& out) const {
  for (const CachedPlacements& c : cache_) {
    if (!c.valid || c.key != key || c.generation != generation_ || c.copy != out.copy) continue;
    out.axis_count = c.axis_count;
    out.any_malformed = c.any_malformed;
    out.shape_id = c.shape_id;
    std::copy(c.axes.begin(), c.axes.begin() + static_cast<std::ptrdiff_t>(c.axis_count),
              out.axes.begin());
    return true;
  }
  return false;
}

void Decoder::toCache(std::uint64_t key, FrameDecode& out) {
  if (out.axis_count > kCachedAxes) return;
  out.shape_id = ++last_shape_id_;
  CachedPlacements& c = cache_[cache_next_];
  cache_next_ = (cache_next_ + 1) % cache_.size();
  c.valid = true;
  c.key = key;
  c.generation = generation_;
  c.copy = out.copy;
  c.any_malformed = out.any_malformed;
  c.shape_id = out.shape_id;
  c.axis_count = out.axis_count;
  std::copy(out.axes.begin(), out.axes.begin() + static_cast<std::ptrdiff_t>(out.axis_count),
            c.axes.begin());
}

// docs/protocol.md §8: a frame with any WKC above zero is a returned copy; otherwise the frame
// after a master's frame with the same datagram list is its returned copy.
void Decoder::classifyCopy(const EcatFrame& frame, std::uint64_t signature, bool any_wkc,
                           FrameDecode& out) {
  out.paired = previous_was_master_ && signature == previous_signature_;
  if (any_wkc) {
    out.copy = CopyKind::Returned;
  } else if (out.paired) {
    out.copy = CopyKind::Returned;
  } else {
    out.copy = CopyKind::Master;
  }
  previous_signature_ = signature;
  if (out.copy == CopyKind::Master) out.paired = false;
  previous_was_master_ = out.copy == CopyKind::Master && frame.count > 0;
}

AxisPlacement* Decoder::placementFor(FrameDecode& out, std::uint16_t axis) {
  // Placements usually arrive in axis order: the last one, or a new one after it.
  if (out.axis_count > 0 && out.axes[out.axis_count - 1].axis == axis) {
    return &out.axes[out.axis_count - 1];
  }
  const bool after_last = out.axis_count == 0 || out.axes[out.axis_count - 1].axis < axis;
  for (std::size_t i = 0; !after_last && i < out.axis_count; ++i) {
    if (out.axes[i].axis == axis) return &out.axes[i];
  }
  if (out.axis_count >= out.axes.size()) return nullptr;
  AxisPlacement& placement = out.axes[out.axis_count++];
  placement = AxisPlacement{};
  placement.axis = axis;
  return &placement;
}

// Records that `axis`'s PDO starts `start` bytes into the datagram's data. A region that is not
// wholly captured is malformed; inputs count only in a returned copy whose WKC (where captured)
// is above zero.
void Decoder::placeRegion(const Datagram& dg, std::uint16_t dg_index, std::size_t start, Pdo pdo,
                          bool returned, FrameDecode& out, std::uint16_t axis) {
  AxisPlacement* placement = placementFor(out, axis);
  if (placement == nullptr) return;
  const std::size_t size = sizeOfPdo(pdo);
  const bool captured = start + size <= dg.length && start + size <= dg.data_captured;
  if (pdo == Pdo::Rx) {
    placement->rx_placed = true;
    placement->rx_datagram = dg_index;
    placement->rx_offset = dg.data_offset + start;
    placement->has_rx = captured;
    placement->rx_malformed = !captured;
  } else {
    placement->tx_placed = true;
    placement->tx_datagram = dg_index;
    placement->tx_offset = dg.data_offset + start;
    // A WKC the capture cut off cannot say the inputs are invalid: they were captured.
    placement->has_tx = captured && returned && (!dg.has_wkc || dg.wkc > 0);
    placement->tx_malformed = returned && !captured;
  }
}

void Decoder::placeConfigured(const EcatFrame& frame, FrameDecode& out) {
  const bool returned = out.copy == CopyKind::Returned;
  for (std::size_t d = 0; d < frame.count; ++d) {
    const Datagram& dg = frame.datagrams[d];
    const auto dg_index = static_cast<std::uint16_t>(d);
    const bool logical = ecat::isLogical(dg.command);
    const bool fp =
        dg.command == ecat::kFprd || dg.command == ecat::kFpwr || dg.command == ecat::kFprw;
    if (!logical && !fp) continue;
    const bool writes = ecat::writesSlaves(dg.command);
    const bool reads = ecat::readsSlaves(dg.command);
    const std::uint64_t base = logical ? dg.address : dg.ado();
    const std::vector<AxisConfig>& axes = placedAxes();
    for (std::size_t a = 0; a < axes.size(); ++a) {
      const AxisConfig& axis = axes[a];
      const auto axis_index = static_cast<std::uint16_t>(a);
      if (logical == axis.physical()) continue;
      if (fp && *axis.station != dg.adp()) continue;
      const auto outputs = logical ? std::optional<std::uint64_t>(axis.outputs)
                                   : std::optional<std::uint64_t>(axis.sm_outputs);
      const auto inputs = logical ? std::optional<std::uint64_t>(axis.inputs)
                                  : std::optional<std::uint64_t>(axis.sm_inputs);
      if (outputs && writes) {
        Overlap o = overlap(base, dg.length, *outputs, kRxPdoSize);
        // A region that straddles the datagram's end is inconsistent: placed, and malformed.
        if (o != Overlap::None) {
          placeRegion(dg, dg_index, o == Overlap::Inside ? *outputs - base : dg.length, Pdo::Rx,
                      returned, out, axis_index);
        }
      }
      if (inputs && reads) {
        Overlap o = overlap(base, dg.length, *inputs, kTxPdoSize);
        if (o != Overlap::None) {
          placeRegion(dg, dg_index, o == Overlap::Inside ? *inputs - base : dg.length, Pdo::Tx,
                      returned, out, axis_index);
        }
      }
    }
  }
}

}  // namespace ncservo
