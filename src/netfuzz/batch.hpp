// The fast path: pipelinable cases spread over a few long-lived connections ("lanes"), many
// frames per send, each lane closed by an in-stream probe (the fence). Answers are matched by
// transaction id and judged on the fly; anything odd (a verdict, a close, a timeout, an answer
// nobody asked for) makes the affected cases suspects, which the campaign re-runs one by one
// on fresh connections (executor) to attribute and confirm the finding.
#pragma once

#include <cstdint>
#include <vector>

#include "net/socket.hpp"
#include "netfuzz/case.hpp"
#include "netfuzz/oracle.hpp"

namespace mbstorm::netfuzz {

struct BatchOptions {
    unsigned lanes = 4;
    int timeout_ms = 1000;
};

struct BatchResult {
    std::vector<std::size_t> suspects;        // case indexes to re-run in isolation, ascending
    std::vector<std::size_t> answered_valid;  // valid requests answered normally (corpus)
    bool lane_lost = false;                   // a lane was closed, reset or timed out
    bool connect_failed = false;              // a lane could not (re)connect
};

class BatchRunner {
  public:
    BatchRunner(const net::Endpoint& target, const TargetProfile& profile, BatchOptions options);
    ~BatchRunner();
    BatchRunner(const BatchRunner&) = delete;
    BatchRunner& operator=(const BatchRunner&) = delete;

    // Every case must be pipelinable. Case i goes to lane i % lanes.
    BatchResult run(const std::vector<Case>& cases);
    void close_all() noexcept;

  private:
    struct Lane;
    const net::Endpoint& target_;
    const TargetProfile& profile_;
    BatchOptions options_;
    std::vector<Lane*> lanes_;
};

}  // namespace mbstorm::netfuzz
