// The HTTP face of `monitor --metrics [ADDR:]PORT`: GET /metrics answers with the board's last
// snapshot (Debian's cpp-httplib, on threads of its own: two workers, one request per
// connection, so that a flood of scrapes takes at most two threads' share from the capture).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "ncservo/base/error.hpp"
#include "ncservo/telemetry/live_metrics.hpp"

namespace ncservo {

// Where to listen: "9100" (every address), "127.0.0.1:9100", "[::1]:9100", "localhost:0" (a
// port the system picks).
struct ListenAddress {
  std::string host;
  int port = 0;
};
Result<ListenAddress> parseListenAddress(std::string_view text);

class MetricsServer {
 public:
  // Listening once it returns; the board must outlive the server.
  static Result<std::unique_ptr<MetricsServer>> start(const ListenAddress& address,
                                                      const MetricsBoard& board);
  ~MetricsServer();  // stops it
  MetricsServer(const MetricsServer&) = delete;
  MetricsServer& operator=(const MetricsServer&) = delete;
  int port() const;  // the one bound (the system's pick for port 0)
  // Scrapes answered so far, and the time spent formatting them (docs/field.md#metrics).
  std::uint64_t scrapes() const;
  double scrapeSeconds() const;

 private:
  struct State;
  explicit MetricsServer(std::unique_ptr<State> state);
  std::unique_ptr<State> state_;
};

}  // namespace ncservo
