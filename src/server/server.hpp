// The io_uring Modbus TCP reference slave: N worker threads, each with its own ring and its
// own SO_REUSEPORT listener on the same port. Start it in-process (tests, `mbstorm run`) or
// from `mbstorm serve`.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "server/config.hpp"
#include "server/stats.hpp"
#include "util/error.hpp"

namespace mbstorm::server {

class Worker;

class Server {
  public:
    explicit Server(ServerConfig config);
    ~Server();  // stops and joins
    Server(const Server&) = delete;
    Server& operator=(const Server&) = delete;

    // Binds, starts the threads and returns once every ring is serving. Else why not:
    // InvalidInput (the listen address, fault settings), Network (the listen itself),
    // Unsupported (the backend asked for, a ring that cannot be set up).
    Error start();
    // Asks every thread to stop, waits for them. Idempotent.
    void stop() noexcept;
    bool running() const noexcept { return running_; }

    std::uint16_t port() const noexcept { return port_; }
    std::string endpoint() const;  // "127.0.0.1:40123"
    unsigned threads() const noexcept { return static_cast<unsigned>(workers_.size()); }
    const ServerConfig& config() const noexcept { return config_; }
    slave::DataModel& model() noexcept { return *model_; }

    ServerStats stats() const noexcept;
    // Non-fatal problems found by start(), e.g. an open-files limit below max_connections.
    const std::string& warning() const noexcept { return warning_; }
    // One line about the I/O path, e.g. "io_uring: multishot recv + buffer ring (2048 x 4096)".
    std::string describe_io() const;
    // Why auto chose epoll ("" when io_uring runs or epoll was asked for).
    const std::string& backend_reason() const noexcept { return backend_why_; }
    // Fixed bytes per open connection (excluding the kernel socket).
    static std::size_t bytes_per_connection() noexcept;

  private:
    // Raises the descriptor limit, or lowers max_connections below it (with a warning).
    void fit_connection_limit_to_descriptors(unsigned threads);
    // Direct descriptors: each thread's socket table (its share of max_connections with room
    // for an uneven spread, at most the open-files limit); may add threads when `threads` was
    // not set, or lower max_connections (with a warning). Returns the slots per table.
    unsigned fit_socket_tables(unsigned& threads);

    ServerConfig config_;
    std::unique_ptr<slave::DataModel> owned_model_;
    // RTU over TCP with no models given: one shared model whose unit 0 is a broadcast.
    std::unique_ptr<slave::UnitModels> owned_units_;
    slave::DataModel* model_ = nullptr;
    std::vector<std::unique_ptr<Worker>> workers_;
    std::vector<std::thread> threads_;
    std::atomic<std::uint32_t> open_connections_{0};
    std::uint16_t port_ = 0;
    std::string host_;
    std::string warning_;
    std::string backend_why_;
    unsigned table_slots_ = 0;  // per thread; 0: plain descriptors
    bool running_ = false;
    // Simulated inputs: one thread writes them every simulate_interval_ms until stop().
    std::unique_ptr<slave::Simulator> simulator_;
    std::thread simulator_thread_;
    std::atomic<bool> simulator_stop_{false};
};

}  // namespace mbstorm::server
