// The fuzzer's link to a device on a serial line (--serial): one tty, opened once and shared
// by every link the runners open (a line has one master; the runners hold one link at a time
// there, max_links() == 1). Each send() is put on the line after the inter-frame silence
// (t3.5), in one piece, so a case's frames and gaps reach the device as the case says.
#pragma once

#include <memory>
#include <string>

#include "net/serial_port.hpp"
#include "netfuzz/link.hpp"

namespace mbstorm::netfuzz {

class SerialLink final : public Link {
  public:
    explicit SerialLink(std::shared_ptr<net::SerialPort> port) noexcept : port_(std::move(port)) {}
    int poll_fd() const noexcept override { return port_->fd(); }
    ssize_t send(const std::uint8_t* data, std::size_t size) noexcept override;
    ssize_t recv(std::uint8_t* data, std::size_t size) noexcept override;
    void shutdown_write() noexcept override {}  // a line cannot be half-closed

  private:
    std::shared_ptr<net::SerialPort> port_;
};

class SerialConnector final : public Connector {
  public:
    SerialConnector(std::string device, const net::SerialSettings& settings, codec::Framing framing)
        : device_(std::move(device)), settings_(settings), framing_(framing) {}
    // The line (opened on first use); input left from earlier links is dropped.
    std::unique_ptr<Link> open(int timeout_ms, int& error) override;
    unsigned max_links() const noexcept override { return 1; }
    std::string describe() const override;
    codec::Framing framing() const noexcept override { return framing_; }
    bool serial_line() const noexcept override { return true; }
    std::int64_t intercharacter_timeout_ns() const noexcept override {
        return net::intercharacter_timeout_ns(settings_);
    }

  private:
    std::string device_;
    net::SerialSettings settings_;
    codec::Framing framing_;
    std::shared_ptr<net::SerialPort> port_;
};

}  // namespace mbstorm::netfuzz
