#include "ncservo/telemetry/mqtt_publisher.hpp"

#include <fmt/format.h>
#include <mosquitto.h>
#include <unistd.h>

#include <condition_variable>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <thread>

#include "ncservo/base/number.hpp"

namespace ncservo {

const char* mqttTopicName(MqttTopic topic) {
  for (const MqttTopicRow& row : kMqttTopics) {
    if (row.topic == topic) return row.name;
  }
  return "";
}

Result<MqttTarget> parseMqttUrl(std::string_view url) {
  MqttTarget target;
  std::string_view rest;
  if (url.substr(0, 7) == "mqtt://") {
    rest = url.substr(7);
  } else if (url.substr(0, 8) == "mqtts://") {
    rest = url.substr(8);
    target.tls = true;
    target.port = 8883;
  } else {
    return fail(fmt::format("--mqtt {}: expected mqtt://HOST[:PORT]/PREFIX or mqtts://…", url));
  }
  const std::size_t slash = rest.find('/');
  std::string_view authority = rest.substr(0, slash);
  std::string_view prefix = slash == std::string_view::npos ? "" : rest.substr(slash + 1);
  while (!prefix.empty() && prefix.back() == '/') prefix.remove_suffix(1);
  if (prefix.empty()) return fail(fmt::format("--mqtt {}: no topic prefix after the host", url));
  if (prefix.find_first_of("#+") != std::string_view::npos) {
    return fail(fmt::format("--mqtt {}: a topic prefix cannot hold the wildcards # or +", url));
  }
  const std::size_t colon = authority.rfind(':');
  if (colon != std::string_view::npos && authority.find(']', colon) == std::string_view::npos) {
    const auto port = parseNumber<int>(authority.substr(colon + 1));
    if (!port || *port < 1 || *port > 65535) {
      return fail(fmt::format("--mqtt {}: the port is not a number of 1 to 65535", url));
    }
    target.port = *port;
    authority = authority.substr(0, colon);
  }
  if (authority.size() >= 2 && authority.front() == '[' && authority.back() == ']') {
    authority = authority.substr(1, authority.size() - 2);
  }
  if (authority.empty()) return fail(fmt::format("--mqtt {}: no host", url));
  target.host = authority;
  target.prefix = prefix;
  return target;
}

namespace {

struct Message {
  std::string topic;
  std::string payload;
  bool retain = false;
  std::optional<int> mid;  // sent on this connection, waiting for its PUBACK
};

// Messages handed to libmosquitto and not yet acknowledged, at most. libmosquitto's default of 20
// caps a publisher at 20 messages a round trip, fewer than a faulty bus's findings on a loaded
// machine (docs/field.md#how-fast); the rest wait in the queue, where the oldest can be dropped.
constexpr int kInFlight = 1000;

void initLibrary() {
  static std::once_flag once;
  std::call_once(once, [] { mosquitto_lib_init(); });
}

}  // namespace

// Three parties: the capture thread (publish, notes), libmosquitto's network thread (the
// callbacks) and the sending thread, which alone owns the queue and calls mosquitto_publish. The
// first two only touch what the mutex guards, briefly.
struct MqttPublisher::State {
  MqttOptions options;
  mosquitto* mosq = nullptr;
  std::mutex mutex;
  std::condition_variable wake;
  // Guarded by mutex.
  std::deque<Message> incoming;
  std::vector<int> acked;
  bool connected = false;
  bool reconnected = false;  // every message not acknowledged goes again
  enum class Phase : std::uint8_t { Running, Draining, Ending } phase = Phase::Running;
  std::uint64_t dropped = 0;
  std::size_t pending = 0;  // messages in the sender's queue, for finish()
  std::vector<std::string> notes;
  bool said_dropping = false;
  // The sending thread's own.
  std::map<std::uint64_t, Message> queue;  // by sequence number: the oldest first
  std::map<int, std::uint64_t> in_flight;  // mid -> sequence number
  std::uint64_t next_sequence = 0;
  std::uint64_t first_unsent = 0;  // the messages from here on were not handed to libmosquitto
  std::thread sender;

  std::string topic(MqttTopic t) const { return options.target.prefix + "/" + mqttTopicName(t); }
  void send();
  void dropOldest(std::size_t limit);
};

// The oldest of the messages not yet sent go: those in flight are libmosquitto's already.
void MqttPublisher::State::dropOldest(std::size_t limit) {
  std::size_t gone = 0;
  auto oldest = queue.lower_bound(first_unsent);
  while (queue.size() > limit && oldest != queue.end()) {
    oldest = queue.erase(oldest);
    ++gone;
  }
  if (gone == 0) return;
  const std::lock_guard lock(mutex);
  dropped += gone;
  if (!said_dropping) {
    notes.push_back(fmt::format("--mqtt: the queue holds {} messages: dropping the oldest",
                                options.queue_limit));
    said_dropping = true;
  }
}

void MqttPublisher::State::send() {
  std::unique_lock lock(mutex);
  while (true) {
    wake.wait_for(lock, std::chrono::milliseconds(100), [this] {
      return !incoming.empty() || !acked.empty() || reconnected || phase == Phase::Ending;
    });
    std::deque<Message> arrived;
    arrived.swap(incoming);
    std::vector<int> done;
    done.swap(acked);
    const bool again = reconnected;
    reconnected = false;
    const bool online = connected;
    const Phase now = phase;
    lock.unlock();
    for (Message& m : arrived) queue.emplace(next_sequence++, std::move(m));
    for (const int mid : done) {
      const auto found = in_flight.find(mid);
      if (found == in_flight.end()) continue;  // a message dropped while it waited
      queue.erase(found->second);
      in_flight.erase(found);
    }
    dropOldest(options.queue_limit);
    if (again) {
      in_flight.clear();
      for (auto& entry : queue) entry.second.mid.reset();
      first_unsent = queue.empty() ? next_sequence : queue.begin()->first;
    }
    if (online) {
      for (auto next = queue.lower_bound(first_unsent);
           next != queue.end() && in_flight.size() < std::size_t{kInFlight}; ++next) {
        Message& m = next->second;
        int mid = 0;
        const int rc =
            mosquitto_publish(mosq, &mid, m.topic.c_str(), static_cast<int>(m.payload.size()),
                              m.payload.data(), 1, m.retain);
        if (rc != MOSQ_ERR_SUCCESS) break;  // not connected after all: again on reconnecting
        m.mid = mid;
        in_flight[mid] = next->first;
        first_unsent = next->first + 1;
      }
    }
    lock.lock();
    pending = queue.size();
    if (now == Phase::Ending) return;
  }
}

MqttPublisher::MqttPublisher(std::unique_ptr<State> state) : state_(std::move(state)) {}

Result<std::unique_ptr<MqttPublisher>> MqttPublisher::start(const MqttOptions& options) {
  initLibrary();
  auto state = std::make_unique<State>();
  State& s = *state;
  s.options = options;
  if (s.options.client_id.empty()) {
    char host[256] = {};
    gethostname(host, sizeof host - 1);
    s.options.client_id = fmt::format("ncservo-{}-{}", host, getpid());
  }
  s.mosq = mosquitto_new(s.options.client_id.c_str(), true, &s);
  if (s.mosq == nullptr) return fail("--mqtt: libmosquitto could not make a client");
  mosquitto_int_option(s.mosq, MOSQ_OPT_PROTOCOL_VERSION, MQTT_PROTOCOL_V311);
  mosquitto_int_option(s.mosq, MOSQ_OPT_SEND_MAXIMUM, kInFlight);
  const std::string status = s.topic(MqttTopic::Presence);
  if (mosquitto_will_set(s.mosq, status.c_str(), 7, "offline", 1, true) != MOSQ_ERR_SUCCESS) {
    return fail(fmt::format("--mqtt: {} is not a topic", status));
  }
  if (options.target.tls) {
    const char* ca = options.ca_file.empty() ? nullptr : options.ca_file.c_str();
    const int rc =
        mosquitto_tls_set(s.mosq, ca, ca == nullptr ? "/etc/ssl/certs" : nullptr,
                          options.cert_file.empty() ? nullptr : options.cert_file.c_str(),
                          options.key_file.empty() ? nullptr : options.key_file.c_str(), nullptr);
    if (rc != MOSQ_ERR_SUCCESS) {
      return fail(fmt::format("--mqtt-ca, --mqtt-cert, --mqtt-key: {}", mosquitto_strerror(rc)));
    }
  }
  mosquitto_connect_callback_set(s.mosq, [](mosquitto* mosq, void* self, int rc) {
    State& st = *static_cast<State*>(self);
    {
      const std::lock_guard lock(st.mutex);
      st.connected = rc == 0;
      st.reconnected = rc == 0;
      st.notes.push_back(rc == 0
                             ? fmt::format("--mqtt: connected to {}:{} ({} messages waiting)",
                                           st.options.target.host, st.options.target.port,
                                           st.pending + st.incoming.size())
                             : fmt::format("--mqtt: refused: {}", mosquitto_connack_string(rc)));
    }
    if (rc == 0) {
      const std::string topic = st.topic(MqttTopic::Presence);
      mosquitto_publish(mosq, nullptr, topic.c_str(), 6, "online", 1, true);
    }
    st.wake.notify_one();
  });
  mosquitto_disconnect_callback_set(s.mosq, [](mosquitto*, void* self, int rc) {
    State& st = *static_cast<State*>(self);
    const std::lock_guard lock(st.mutex);
    if (st.connected && rc != 0) {
      st.notes.push_back("--mqtt: connection lost; the messages wait for the broker");
    }
    st.connected = false;
  });
  mosquitto_publish_callback_set(s.mosq, [](mosquitto*, void* self, int mid) {
    State& st = *static_cast<State*>(self);
    {
      const std::lock_guard lock(st.mutex);
      st.acked.push_back(mid);
    }
    st.wake.notify_one();
  });
  mosquitto_reconnect_delay_set(s.mosq, 1, 4, false);
  const int rc =
      mosquitto_connect_async(s.mosq, options.target.host.c_str(), options.target.port, 10);
  if (rc != MOSQ_ERR_SUCCESS) {
    // Tried again by the network thread; the messages wait meanwhile.
    s.notes.push_back(fmt::format("--mqtt: {}:{}: {}; trying again", options.target.host,
                                  options.target.port, mosquitto_strerror(rc)));
  }
  if (mosquitto_loop_start(s.mosq) != MOSQ_ERR_SUCCESS) {
    mosquitto_destroy(s.mosq);
    return fail("--mqtt: libmosquitto could not start its network thread");
  }
  s.sender = std::thread([&s] { s.send(); });
  return std::unique_ptr<MqttPublisher>(new MqttPublisher(std::move(state)));
}

void MqttPublisher::publish(MqttTopic topic, std::string payload) {
  State& s = *state_;
  {
    const std::lock_guard lock(s.mutex);
    s.incoming.push_back({s.topic(topic), std::move(payload), topic == MqttTopic::Presence, {}});
    if (s.incoming.size() > s.options.queue_limit) {
      s.incoming.pop_front();
      ++s.dropped;
    }
  }
  s.wake.notify_one();
}

std::size_t MqttPublisher::finish(std::chrono::milliseconds timeout) {
  State& s = *state_;
  if (!s.sender.joinable()) return 0;
  publish(MqttTopic::Presence, "offline");
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  std::size_t left = 0;
  {
    std::unique_lock lock(s.mutex);
    s.phase = State::Phase::Draining;
    s.pending = 1;  // until the sender has taken the last messages in
    while (std::chrono::steady_clock::now() < deadline &&
           (s.pending > 0 || !s.incoming.empty() || !s.acked.empty())) {
      lock.unlock();
      s.wake.notify_one();
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      lock.lock();
    }
    s.phase = State::Phase::Ending;  // the sender ends at its next turn, whatever is left
  }
  s.wake.notify_one();
  s.sender.join();
  // The sender's last turn took the last messages in (and dropped past the limit): what its
  // queue still holds was never acknowledged.
  left = s.queue.size() + s.incoming.size();
  mosquitto_disconnect(s.mosq);
  mosquitto_loop_stop(s.mosq, false);
  return left;
}

MqttPublisher::~MqttPublisher() {
  if (state_->sender.joinable()) finish(std::chrono::milliseconds(0));
  mosquitto_destroy(state_->mosq);
}

std::uint64_t MqttPublisher::dropped() const {
  const std::lock_guard lock(state_->mutex);
  return state_->dropped;
}

std::vector<std::string> MqttPublisher::notes() {
  std::vector<std::string> out;
  const std::lock_guard lock(state_->mutex);
  out.swap(state_->notes);
  return out;
}

}  // namespace ncservo
