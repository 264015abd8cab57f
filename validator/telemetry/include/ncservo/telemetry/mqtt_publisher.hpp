// `monitor --mqtt mqtt[s]://HOST[:PORT]/PREFIX` (docs/field.md#mqtt): each finding, incident,
// drive message and link fault as its JSON Lines object on PREFIX/<topic>, QoS 1, through Debian's
// libmosquitto and its network thread. Nothing waits for the network: messages go into a bounded
// queue (the oldest dropped first, counted) and stay there until the broker acknowledged them
// (PUBACK); after a reconnection every one not acknowledged is sent again, so a broker that went
// away or restarted loses nothing, and a subscriber may see a message twice (QoS 1), told by its
// fingerprint and frame.
#pragma once

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "ncservo/base/error.hpp"

namespace ncservo {

// The topics, under the prefix: what each carries.
enum class MqttTopic : std::uint8_t { Finding, Incident, DriveMessage, LinkFault, Presence };
struct MqttTopicRow {
  MqttTopic topic;
  const char* name;
  const char* carries;
};
inline constexpr std::array<MqttTopicRow, 5> kMqttTopics{{
    {MqttTopic::Finding, "finding", "each finding as it happens, JSON Lines' finding object"},
    {MqttTopic::Incident, "incident",
     "each incident once it ended (recovered, or the next fault came) or the capture did, JSON "
     "Lines' incident object"},
    {MqttTopic::DriveMessage, "drive-message",
     "each emergency, SDO answer and abort, JSON Lines' drive_message object"},
    {MqttTopic::LinkFault, "link-fault", "each link fault, JSON Lines' link_fault object"},
    {MqttTopic::Presence, "status",
     "\"online\" once connected, \"offline\" at the end or as the broker's last will; retained"},
}};
const char* mqttTopicName(MqttTopic topic);

struct MqttTarget {
  bool tls = false;
  std::string host;
  int port = 1883;
  std::string prefix;  // no leading or trailing '/'
};
// mqtt://HOST[:PORT]/PREFIX or mqtts://… (port 1883 or 8883 unless given).
Result<MqttTarget> parseMqttUrl(std::string_view url);

struct MqttOptions {
  MqttTarget target;
  std::string client_id;            // empty: ncservo-HOSTNAME-PID
  std::string ca_file;              // mqtts: the broker's CA (empty: the system's, /etc/ssl/certs)
  std::string cert_file, key_file;  // mqtts: a client certificate, when the broker wants one
  std::size_t queue_limit = 10000;  // messages kept at most
};

class MqttPublisher {
 public:
  // Connects in the background: a broker not there yet is tried again every few seconds.
  static Result<std::unique_ptr<MqttPublisher>> start(const MqttOptions& options);
  ~MqttPublisher();
  MqttPublisher(const MqttPublisher&) = delete;
  MqttPublisher& operator=(const MqttPublisher&) = delete;

  // Never waits: queued for the sending thread; the oldest is dropped when the queue is full.
  void publish(MqttTopic topic, std::string payload);
  // The end: waits up to `timeout` for every message to be acknowledged, then says "offline"
  // and disconnects. Returns the messages left unacknowledged.
  std::size_t finish(std::chrono::milliseconds timeout);
  std::uint64_t dropped() const;
  // What happened since the last call, one line each (connected, lost, dropping), for the
  // capture thread to print.
  std::vector<std::string> notes();

  struct State;

 private:
  explicit MqttPublisher(std::unique_ptr<State> state);
  std::unique_ptr<State> state_;
};

}  // namespace ncservo
