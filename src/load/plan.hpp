// A load plan: everything `mbstorm run` needs to know, as plain data. The scenario layer fills
// it from YAML, the CLI from flags; validate_plan() is the single check both rely on.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "codec/framing.hpp"
#include "codec/function_code.hpp"
#include "net/serial_port.hpp"
#include "net/tls_context.hpp"
#include "util/error.hpp"

namespace mbstorm::load {

using Duration = std::chrono::nanoseconds;

enum class AddressMode : std::uint8_t { Sequential, Uniform, Zipf };
enum class ValueMode : std::uint8_t { Constant, Counter, Random, Pattern };
enum class LoadModel : std::uint8_t { ClosedLoop, OpenLoop };
enum class Arrival : std::uint8_t { Even, Poisson };
enum class Ramp : std::uint8_t { Constant, Linear };

// How write operations choose the values they write.
struct ValueSpec {
    ValueMode mode = ValueMode::Constant;
    std::uint16_t value = 0;             // Constant: the value; Counter: the first value
    std::uint16_t step = 1;              // Counter: added after every value (wraps at 65536)
    std::vector<std::uint16_t> pattern;  // Pattern: cycled in order
    bool operator==(const ValueSpec&) const = default;
};

// One entry of the weighted operation mix.
struct Operation {
    std::string name;  // shown in errors and reports; defaults to the function name
    std::uint8_t function = codec::to_byte(codec::FunctionCode::ReadHoldingRegisters);
    std::uint8_t unit_id = 1;
    // Every request stays inside [first_address, last_address]. When last_address is unset
    // the operation always starts at first_address.
    std::uint16_t first_address = 0;
    std::optional<std::uint16_t> last_address;
    std::uint16_t quantity = 1;  // registers or coils (FC17: registers read)
    AddressMode address_mode = AddressMode::Sequential;
    // Sequential: the first request starts this many addresses past first_address (rounded
    // down to a whole block, wrapped into the range). Shards start apart (load/shard.hpp).
    std::uint32_t start_offset = 0;
    double zipf_exponent = 1.0;  // AddressMode::Zipf: P(rank k) ~ 1 / k^exponent
    ValueSpec values;            // write functions only
    std::uint32_t weight = 1;
    // Function-specific extras.
    std::uint16_t write_quantity = 1;  // FC17: registers written (at the same start address)
    std::uint16_t and_mask = 0x0000;   // FC16: the OR mask comes from `values`
    std::uint16_t sub_function = 0;    // FC08 (only 0x0000, return query data, is generated)
    std::uint8_t device_id_code = 1;   // FC2B/0E
    bool operator==(const Operation&) const = default;
};

// A stage of a staged run (see stage_schedule.hpp). Unset targets keep the previous stage's
// value; a linear stage ramps to its targets, a constant one holds them from its start. The
// engine changes the rate and the connection count live: connections stay open across stages.
struct Stage {
    Duration duration{};
    std::optional<double> target_rate;                // open loop only; 0 pauses sending
    std::optional<std::uint32_t> target_connections;  // 0 closes every connection
    Ramp ramp = Ramp::Constant;
    std::string name;  // for reports; default "stage N"
    bool operator==(const Stage&) const = default;
};

struct Plan {
    // Target.
    std::string host = "127.0.0.1";  // numeric IPv4/IPv6 or a host name
    // Modbus/TCP Security: set, every connection is TLS (mutual authentication), MBAP inside;
    // `tls_resume` offers the previous session when a connection reopens.
    std::shared_ptr<net::TlsContext> tls;
    bool tls_resume = false;
    std::uint16_t port = 502;
    // Local addresses the connections are bound to, round-robin (net/source_addresses.hpp's
    // list and range syntax); empty: the kernel picks. Each address has its own ephemeral
    // ports, so N addresses hold N times the connections one can towards the target.
    std::string source_addresses;
    // Mbap: Modbus TCP. Rtu: RTU over TCP (no transaction ids: depth must be 1).
    codec::Framing framing = codec::Framing::Mbap;

    // run --serial: load this serial line instead of a TCP target (device empty: TCP). One
    // master, one request on the line at a time: connections and depth do not apply.
    struct Serial {
        std::string device;
        net::SerialSettings line;
        codec::Framing framing = codec::Framing::Rtu;
        bool operator==(const Serial&) const = default;
    } serial;

    std::vector<Operation> operations;

    // Load model.
    LoadModel model = LoadModel::ClosedLoop;
    std::uint32_t depth = 1;  // closed loop: outstanding per connection; open loop: the cap
    double rate = 0;          // open loop: total transactions per second over all threads
    Arrival arrival = Arrival::Even;

    // Connections and threads.
    std::uint32_t connections = 1;
    std::uint32_t threads = 0;    // 0: one per core (never more than connections)
    double connect_rate = 10000;  // connections opened per second over all threads
    Duration connect_timeout = std::chrono::seconds(3);
    Duration transaction_timeout = std::chrono::seconds(1);
    Duration reconnect_backoff_min = std::chrono::milliseconds(100);
    Duration reconnect_backoff_max = std::chrono::seconds(5);

    // Length of the run: by time, by transaction count, or both (whichever ends first).
    // With stages the run lasts warm-up + the sum of the stage durations instead.
    Duration duration = std::chrono::seconds(10);  // 0: no time limit (needs `transactions`)
    std::uint64_t transactions = 0;  // 0: no count limit; measured sends only (after warm-up)
    Duration warmup{};               // excluded from the results

    std::vector<Stage> stages;

    // Open loop: a send later than its intended time by more than this counts as a late send.
    Duration late_threshold = std::chrono::milliseconds(1);

    bool allow_writes = false;  // see write_safety.hpp
    std::uint64_t seed = 1;

    // Which part of a sharded test this plan is (load/shard.hpp); count 0: not sharded.
    struct Shard {
        std::uint32_t index = 0;
        std::uint32_t count = 0;
        bool operator==(const Shard&) const = default;
    } shard;

    // Member by member (`tls` by pointer): a scenario printed and read back must give the plan
    // it was printed from (the scenario_yaml fuzz harness checks it).
    bool operator==(const Plan&) const = default;
};

// Valid ranges, one place.
inline constexpr std::uint32_t kMaxConnections = 100000;
inline constexpr std::uint32_t kMaxDepth = 32768;  // half the transaction id space
inline constexpr std::uint32_t kMaxThreads = 1024;
inline constexpr double kMaxRate = 1e9;
inline constexpr double kMaxZipfExponent = 10.0;

// What a run's settings say about the load model, before the model is settled: the model
// named (if any), the rate, whether a stage sets a rate, whether an arrival pattern was named.
struct LoadModelAsked {
    std::optional<LoadModel> model;
    double rate = 0;
    bool stage_rate = false;
    bool arrival_given = false;
};

// The contradictions among those settings; flags and scenario keys each word them in their
// own spelling, from this one rule.
enum class LoadModelConflict : std::uint8_t {
    None,
    RateInClosedLoop,     // a rate with the closed loop named: the rate would be ignored
    OpenLoopWithoutRate,  // the open loop named, no rate to pace it
    ArrivalInClosedLoop,  // an arrival pattern with no open loop to space arrivals in
};

// The model the settings mean: open loop when named or when a rate is set anywhere, else
// closed loop. Returns the first contradiction among them (`model` is set regardless).
LoadModelConflict settle_load_model(const LoadModelAsked& asked, LoadModel& model);

// Every problem with a plan, each naming the field and the valid range ("connections: 0 is
// out of range (valid 1..100000)"), joined by "; " in one InvalidInput error. None when the
// plan is usable.
Error validate_plan(const Plan& plan);

// True for the function codes the load generator can produce: every public one whose
// request shape it knows how to fill (all but the file records).
bool is_generatable_function(std::uint8_t fc) noexcept;

// "0x01 read_coils, 0x02 read_discrete_inputs, ..." for every generatable function.
std::string generatable_functions_text();

// Addresses one request of `op` covers from its start (FC17: the larger of its two blocks).
std::uint32_t address_span(const Operation& op) noexcept;

// The operation's last usable start address (the block must end at or before last_address).
std::uint16_t last_start_address(const Operation& op) noexcept;

// The most connections the plan ever asks for (stages included).
std::uint32_t peak_connections(const Plan& plan) noexcept;

// Threads the engine will actually run: plan.threads or the core count, capped at the peak
// connection count.
std::uint32_t effective_threads(const Plan& plan) noexcept;

}  // namespace mbstorm::load
