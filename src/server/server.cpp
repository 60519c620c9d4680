#include "server/server.hpp"

#include <fmt/format.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <thread>

#include "net/clock.hpp"
#include "net/features.hpp"
#include "net/kernel_tls.hpp"
#include "net/socket.hpp"
#include "server/worker.hpp"
#include "slave/data_model.hpp"

namespace mbstorm::server {

Server::Server(ServerConfig config) : config_(std::move(config)) {}

Server::~Server() {
    stop();
}

Error Server::start() {
    auto fail = [&](Error error) {
        stop();
        return error;
    };
    if (running_) return Error::none();
    const Result<net::BackendDecision> backend = net::choose_backend(config_.backend_choice, false);
    if (!backend.ok()) return fail(backend.error());
    config_.backend = backend->backend;
    backend_why_ = backend->why;
    const bool uring = config_.backend == net::Backend::IoUring;
    if (Error invalid = slave::validate(config_.faults); !invalid.ok()) return fail(invalid);
    const Result<net::Endpoint> listen = net::parse_endpoint(config_.listen, config_.default_port);
    if (!listen.ok()) return fail(listen.error());
    net::Endpoint ep = *listen;
    unsigned n = config_.threads ? config_.threads : std::thread::hardware_concurrency();
    if (n == 0) n = 1;
    if (uring && config_.use_direct_descriptors && net::features().direct_descriptors)
        table_slots_ = fit_socket_tables(n);
    else if (config_.max_connections)
        fit_connection_limit_to_descriptors(n);
    // RTU over TCP speaks for serial slaves: unit 0 is a broadcast there, carried out by every
    // unit and answered by none (models given by a device file are set so by the caller).
    if (config_.framing == codec::Framing::Rtu && !config_.units && !config_.model) {
        owned_units_ = std::make_unique<slave::UnitModels>(slave::UnitModels::shared());
        owned_units_->broadcast_unit_zero = true;
        config_.units = owned_units_.get();
    }
    if (config_.units) {
        model_ = &config_.units->model_at(0);
    } else if (config_.model) {
        model_ = config_.model;
    } else {
        owned_model_ = std::make_unique<slave::DataModel>();
        model_ = owned_model_.get();
    }
    const std::uint64_t stall_origin = static_cast<std::uint64_t>(net::now_ns());
    for (unsigned i = 0; i < n; ++i) {
        Result<net::UniqueFd> listener = net::listen_socket(ep);
        if (!listener.ok())
            return fail(std::move(listener).error().prefixed("cannot listen on " + ep.to_string()));
        const int fd = listener->release();  // the worker owns it
        // Accepted sockets inherit these: direct ones cannot be given them afterwards.
        net::set_nodelay(fd);
        if (config_.socket_send_buffer > 0)
            setsockopt(fd, SOL_SOCKET, SO_SNDBUF, &config_.socket_send_buffer,
                       sizeof config_.socket_send_buffer);
        if (i == 0) {
            port_ = net::local_port(fd);
            ep.set_port(port_);  // the other threads join the same (possibly ephemeral) port
            host_ = ep.to_string();
        }
        workers_.push_back(
            std::make_unique<Worker>(config_, *model_, fd, i, open_connections_, stall_origin));
    }
    std::vector<Worker*> peers;
    for (auto& w : workers_) peers.push_back(w.get());
    for (auto& w : workers_) {
        w->set_peers(peers);
        w->set_socket_table(table_slots_);
    }
    for (auto& w : workers_) threads_.emplace_back([wp = w.get()] { wp->run(); });
    running_ = true;
    if (!config_.simulated.empty()) {
        if (!config_.units)
            return fail(
                Error(ErrorCode::InvalidInput, "simulated inputs need the device's unit models"));
        simulator_ = std::make_unique<slave::Simulator>(config_.simulated, *config_.units);
        simulator_stop_ = false;
        simulator_thread_ = std::thread([this] {
            const auto start = net::now_ns();
            const auto interval =
                std::chrono::milliseconds(std::max<std::uint32_t>(1, config_.simulate_interval_ms));
            while (!simulator_stop_.load(std::memory_order_relaxed)) {
                simulator_->update(static_cast<std::uint64_t>(net::now_ns() - start));
                std::this_thread::sleep_for(interval);
            }
        });
    }
    for (auto& w : workers_) {
        while (w->init_status() == 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
        if (w->init_status() < 0) {
            const Error& why = w->setup_error();
            return fail(
                Error(why.code(), fmt::format("cannot set up {}: {}",
                                              net::backend_name(config_.backend), why.message())));
        }
    }
    return Error::none();
}

void Server::fit_connection_limit_to_descriptors(unsigned threads) {
    // Each thread needs a few descriptors of its own (listener, ring, eventfds), and the
    // process has some open already.
    const std::uint64_t per_thread = 8, spare = 16;
    const std::uint64_t wanted = config_.max_connections + 64 + threads * per_thread;
    const std::uint64_t limit = config_.raise_nofile_limit
                                    ? net::raise_nofile_limit(wanted, &warning_)
                                    : net::nofile_limit();
    if (limit == 0 || limit >= wanted) return;
    // Past the descriptor limit accepts fail and nothing is evicted or refused: clients just
    // hang. Below it, the connection limit does its work.
    const std::uint64_t taken = net::open_descriptor_count() + threads * per_thread + spare;
    const std::uint64_t usable = limit > taken ? limit - taken : 1;
    if (usable >= config_.max_connections) return;
    if (warning_.empty()) {
        warning_ = "open-files limit is " + std::to_string(limit) + " but " +
                   std::to_string(wanted) + " are needed";
    }
    warning_ += "; connection limit lowered from " + std::to_string(config_.max_connections) +
                " to " + std::to_string(usable) + " so that the " +
                (config_.full_policy == FullPolicy::Refuse ? "refusal" : "eviction") +
                " of connections still works";
    config_.max_connections = static_cast<std::uint32_t>(usable);
}

unsigned Server::fit_socket_tables(unsigned& threads) {
    // SO_REUSEPORT spreads connections by hash, not evenly: a quarter more room per table.
    auto share = [this](unsigned n) -> std::uint64_t {
        return (std::uint64_t{config_.max_connections} + n - 1) / n * 5 / 4 + 64;
    };
    const std::uint64_t wanted = config_.max_connections ? share(threads) : 65536;
    // Unlimited: the limit in force, as with plain descriptors.
    const std::uint64_t limit = config_.raise_nofile_limit && config_.max_connections != 0
                                    ? net::raise_nofile_limit(wanted, nullptr)
                                    : net::nofile_limit();
    if (limit == 0) return 0;
    if (config_.max_connections == 0) return static_cast<unsigned>(std::min(limit, wanted));
    if (config_.threads == 0) {
        while (share(threads) > limit && threads < 1024) ++threads;
    }
    const std::uint64_t slots = std::min(share(threads), limit);
    // Full tables refuse new connections at accept (handled like running out of descriptors):
    // keep the limit below what the tables hold, so that eviction or refusal does its work.
    if (slots >= share(threads)) return static_cast<unsigned>(slots);
    const std::uint64_t holds = slots * threads * 4 / 5;
    if (holds < config_.max_connections) {
        warning_ = "open-files limit " + std::to_string(limit) +
                   " caps each thread's io_uring socket table; connection limit lowered from " +
                   std::to_string(config_.max_connections) + " to " + std::to_string(holds) +
                   " (more --threads hold more)";
        config_.max_connections = static_cast<std::uint32_t>(std::max<std::uint64_t>(holds, 1));
    }
    return static_cast<unsigned>(slots);
}

void Server::stop() noexcept {
    simulator_stop_ = true;
    if (simulator_thread_.joinable()) simulator_thread_.join();
    for (auto& w : workers_) w->request_stop();
    for (auto& t : threads_)
        if (t.joinable()) t.join();
    threads_.clear();
    running_ = false;
}

std::string Server::endpoint() const {
    return host_;
}

ServerStats Server::stats() const noexcept {
    ServerStats total;
    for (const auto& w : workers_) total += w->counters().snapshot();
    return total;
}

std::size_t Server::bytes_per_connection() noexcept {
    return Worker::connection_bytes();
}

std::string Server::describe_io() const {
    net::Features f = net::features();
    if (config_.backend == net::Backend::Epoll) {  // emulated whatever the kernel has
        f.buf_ring = f.multishot_recv = f.multishot_accept = true;
    }
    const bool br = config_.use_buf_ring && f.buf_ring;
    std::string s = std::string(net::backend_name(config_.backend)) + ", " +
                    std::to_string(workers_.size()) + " thread(s): ";
    // (TLS with the kernel's offload: single-shot recvs, see Worker::setup.)
    const bool ktls = config_.tls && net::kernel_tls().available;
    s +=
        (br && config_.use_multishot_recv && f.multishot_recv && !ktls) ? "multishot recv" : "recv";
    s += br ? " + buffer ring (" + std::to_string(config_.buf_ring_count) + " x " +
                  std::to_string(config_.buf_size) + " B per thread)"
            : " into per-connection buffers";
    s += (config_.use_multishot_accept && f.multishot_accept) ? ", multishot accept" : ", accept";
    if (table_slots_ > 0 && !workers_.empty() && workers_.front()->direct_descriptors())
        s += ", direct descriptors (" + std::to_string(table_slots_) + " slots per thread)";
    s += ", " + std::to_string(bytes_per_connection()) + " B per idle connection";
    return s;
}

}  // namespace mbstorm::server
