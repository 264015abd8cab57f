// The cause table (docs/incidents.md#causes): one row per cause with the evidence it needs and the
// window it looks back over; the first row whose evidence is there names an incident's cause.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ncservo/incidents/incident.hpp"

namespace ncservo {

// What a row looks at (incident_tracks.hpp): the incident's axis, the bus, the fault's SEW.
struct CauseContext;
// What a matching row says: a concrete text, and the frames it read.
struct CauseMatch {
  std::string text;
  std::vector<IncidentEvidence> evidence;
};
using CauseTest = bool (*)(const CauseContext& context, CauseMatch& match);

struct CauseDef {
  CauseId id;
  const char* name;        // the public id, e.g. "communication-loss"
  const char* when;        // the evidence it needs, one line (docs/incidents.md)
  std::int64_t window_ns;  // how far before the incident it looks (0: at the incident only)
  CauseTest test;
};

// Defined in causes.cpp, next to the tests the table names.
extern const std::array<CauseDef, kCauseCount> kCauses;
const CauseDef& causeDef(CauseId id);
// The cause of that public id ("encoder"), if there is one.
std::optional<CauseId> findCause(std::string_view name);

}  // namespace ncservo
