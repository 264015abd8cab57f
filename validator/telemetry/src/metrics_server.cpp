#include "ncservo/telemetry/metrics_server.hpp"

#include <fmt/format.h>
#include <httplib.h>

#include <atomic>
#include <chrono>
#include <thread>

#include "ncservo/base/number.hpp"
#include "ncservo/telemetry/exposition.hpp"

namespace ncservo {

Result<ListenAddress> parseListenAddress(std::string_view text) {
  ListenAddress address{"0.0.0.0", 0};
  std::string_view port = text;
  if (const std::size_t colon = text.rfind(':'); colon != std::string_view::npos) {
    std::string_view host = text.substr(0, colon);
    if (host.size() >= 2 && host.front() == '[' && host.back() == ']') {
      host = host.substr(1, host.size() - 2);  // an IPv6 address in brackets
    }
    if (host.empty()) return fail(fmt::format("--metrics {}: no address before ':'", text));
    address.host = host;
    port = text.substr(colon + 1);
  }
  const auto number = parseNumber<int>(port);
  if (!number || *number < 0 || *number > 65535) {
    return fail(
        fmt::format("--metrics {}: expected [ADDRESS:]PORT, PORT a number of 0 to 65535", text));
  }
  address.port = *number;
  return address;
}

struct MetricsServer::State {
  httplib::Server server;
  std::thread thread;
  int port = 0;
  std::atomic<std::uint64_t> scrapes{0};
  std::atomic<std::uint64_t> scrape_ns{0};
};

MetricsServer::MetricsServer(std::unique_ptr<State> state) : state_(std::move(state)) {}

Result<std::unique_ptr<MetricsServer>> MetricsServer::start(const ListenAddress& address,
                                                            const MetricsBoard& board) {
  auto state = std::make_unique<State>();
  State& s = *state;
  // Two workers, not a pool as large as the machine; each connection closed after its answer,
  // so that an idle keep-alive connection never holds a worker from another scraper.
  s.server.new_task_queue = [] { return new httplib::ThreadPool(2); };
  s.server.set_keep_alive_max_count(1);
  // Not httplib's SO_REUSEPORT: a second monitor on the port would take half the scrapes unseen.
  s.server.set_socket_options([](socket_t sock) {
    const int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  });
  s.server.Get("/metrics", [&board, &s](const httplib::Request&, httplib::Response& response) {
    const auto began = std::chrono::steady_clock::now();
    response.set_content(board.scrape(), kExpositionContentType);
    s.scrape_ns += static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                                  std::chrono::steady_clock::now() - began)
                                                  .count());
    ++s.scrapes;
  });
  if (address.port == 0) {
    s.port = s.server.bind_to_any_port(address.host);
  } else if (s.server.bind_to_port(address.host, address.port)) {
    s.port = address.port;
  } else {
    s.port = -1;
  }
  if (s.port < 0) {
    return fail(fmt::format("--metrics: cannot listen on {}:{} (in use, or no such address)",
                            address.host, address.port));
  }
  s.thread = std::thread([&s] { s.server.listen_after_bind(); });
  // A stop() before the thread listens would go unseen, and the join in the destructor wait.
  for (int i = 0; i < 2000 && !s.server.is_running(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return std::unique_ptr<MetricsServer>(new MetricsServer(std::move(state)));
}

MetricsServer::~MetricsServer() {
  state_->server.stop();
  if (state_->thread.joinable()) state_->thread.join();
}

int MetricsServer::port() const {
  return state_->port;
}
std::uint64_t MetricsServer::scrapes() const {
  return state_->scrapes;
}
double MetricsServer::scrapeSeconds() const {
  return static_cast<double>(state_->scrape_ns) / 1e9;
}

}  // namespace ncservo
