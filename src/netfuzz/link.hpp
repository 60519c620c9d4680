// A byte stream to the fuzz target (TCP, TLS over TCP or a serial line) and what opens one.
// The fuzzer's runners (executor, batch, capacity, campaign) speak only to these, so a new
// transport is a new Link/Connector pair, chosen once by the CLI.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <memory>
#include <string>

#include "codec/framing.hpp"
#include "net/socket.hpp"

namespace mbstorm::netfuzz {

class Link {
  public:
    virtual ~Link() = default;
    virtual int poll_fd() const noexcept = 0;  // what to poll() for readability
    // Bytes already read from poll_fd() but not yet returned by recv() (TLS: decrypted data),
    // which poll() cannot see.
    virtual bool has_buffered_input() const noexcept { return false; }
    // Non-blocking. Bytes taken, or -errno (-EAGAIN: try again once poll_fd() is writable).
    virtual ssize_t send(const std::uint8_t* data, std::size_t size) noexcept = 0;
    // Non-blocking. Bytes read; 0: the peer closed; -EAGAIN: nothing yet; other -errno: broken.
    virtual ssize_t recv(std::uint8_t* data, std::size_t size) noexcept = 0;
    virtual void shutdown_write() noexcept = 0;
    // Bytes sent that the target's program has not read yet, or -1 when that cannot be known
    // (a target on another host, a serial line). A piece of a frame is delivered as a read of
    // its own only once this is 0.
    virtual std::int64_t unread_by_target() const noexcept { return -1; }
};

// Opens links to the target; how (TCP / TLS / serial) is chosen once by the CLI.
struct Connector {
    virtual ~Connector() = default;
    // A connected link, or null with `error` set to an errno value.
    virtual std::unique_ptr<Link> open(int timeout_ms, int& error) = 0;
    // How many links the target can have open at once (a serial line: 1).
    virtual unsigned max_links() const noexcept { return UINT32_MAX; }
    virtual std::string describe() const = 0;
    // How requests and answers are framed on its links.
    virtual codec::Framing framing() const noexcept { return codec::Framing::Mbap; }
    // A serial line: frames are delimited by silences, each send() is one frame's worth of
    // the line after the inter-frame silence, and a gap inside a frame breaks it.
    virtual bool serial_line() const noexcept { return false; }
    // The serial line's inter-character timeout (t1.5) in ns; 0 elsewhere.
    virtual std::int64_t intercharacter_timeout_ns() const noexcept { return 0; }
};

// Modbus TCP or RTU over TCP: a plain non-blocking TCP socket with TCP_NODELAY.
class TcpLink final : public Link {
  public:
    explicit TcpLink(net::UniqueFd fd) noexcept : fd_(std::move(fd)) {}
    int poll_fd() const noexcept override { return fd_.get(); }
    ssize_t send(const std::uint8_t* data, std::size_t size) noexcept override;
    ssize_t recv(std::uint8_t* data, std::size_t size) noexcept override;
    void shutdown_write() noexcept override;
    std::int64_t unread_by_target() const noexcept override;

  private:
    net::UniqueFd fd_;
};

class TcpConnector final : public Connector {
  public:
    explicit TcpConnector(const net::Endpoint& target,
                          codec::Framing framing = codec::Framing::Mbap)
        : target_(target), framing_(framing) {}
    std::unique_ptr<Link> open(int timeout_ms, int& error) override;
    std::string describe() const override { return target_.to_string(); }
    codec::Framing framing() const noexcept override { return framing_; }
    const net::Endpoint& target() const noexcept { return target_; }

  private:
    net::Endpoint target_;
    codec::Framing framing_;
};

// Waits up to `timeout_ms` for `link` to be readable (or to hold buffered input). False on
// timeout; true also on error or hang-up (recv() then tells which).
bool wait_readable(const Link& link, int timeout_ms) noexcept;

}  // namespace mbstorm::netfuzz
