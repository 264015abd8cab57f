#include "ncservo/sim/diagnosis_truth.hpp"

#include <nlohmann/json.hpp>
#include <string_view>

namespace ncservo::sim {

std::string diagnosisJson(const DiagnosisTruth& truth) {
  using Json = nlohmann::ordered_json;
  auto optional = [](const auto& value) { return value ? Json(*value) : Json(); };
  Json messages = Json::array();
  for (const DriveSaid& m : truth.drive_messages) {
    Json item = {{"frame", m.frame},
                 {"request_frame", optional(m.request_frame)},
                 {"station", m.station},
                 {"kind", m.kind}};
    if (std::string_view(m.kind) == "emergency") {
      item["code"] = m.code;
      item["register"] = m.error_register;
    } else {
      item["index"] = m.index;
      item["subindex"] = m.subindex;
      if (m.value) item["value"] = *m.value;
      if (std::string_view(m.kind) == "sdo-abort") item["abort"] = m.abort_code;
    }
    messages.push_back(std::move(item));
  }
  Json errors = Json::array();
  for (const EscErrorTruth& e : truth.esc_errors) {
    errors.push_back({{"frame", e.frame},
                      {"station", e.station},
                      {"port", e.port},
                      {"counter", e.counter},
                      {"delta", e.delta}});
  }
  Json links = Json::array();
  for (const LinkFaultTruth& l : truth.link_faults) {
    links.push_back(
        {{"frame", l.frame}, {"station", l.station}, {"port", l.port}, {"errors", l.errors}});
  }
  return Json{{"drive_messages", messages}, {"esc_errors", errors}, {"link_faults", links}}.dump(
             1) +
         "\n";
}

}  // namespace ncservo::sim
