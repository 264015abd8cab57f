#include "ncservo/al_tracker.hpp"

namespace ncservo {

// Placeholder while the tracker is written; replaced before the ESM rules are claimed.
void AlTracker::onFrame(const EcatFrame&, const ByteReader&, bool, bool, const Stamp&,
                        std::vector<AlFinding>&) {}
std::optional<std::uint8_t> AlTracker::stateOfStation(std::uint16_t) const { return std::nullopt; }
bool AlTracker::enteredOp(std::uint16_t) const { return false; }
const char* alStateName(std::uint8_t) { return "?"; }
bool alTransitionAllowed(std::uint8_t, std::uint8_t) { return true; }

}  // namespace ncservo
