// What the fuzzer knows of the device's data model: which addresses of each of the four tables
// answer, how many items one read may take, whether writes stick, which unit ids answer and
// what an exception costs. Learned before fuzzing (learn_device_model), given by hand (--map)
// or read back from an earlier run's model.json (--device-model), so that most cases land inside
// the map and the code behind each address check runs: real devices have small, sparse maps that do
// not start at 0, and a request outside them only ever meets exception 02.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "codec/table.hpp"
#include "netfuzz/link.hpp"
#include "netfuzz/oracle.hpp"
#include "util/error.hpp"

namespace mbstorm::netfuzz {

struct AddressRange {
    std::uint16_t first = 0, last = 0;  // inclusive
    std::uint32_t size() const noexcept { return std::uint32_t{last} - first + 1; }
    bool operator==(const AddressRange&) const = default;
};

enum class WritesStick : std::uint8_t { Unknown, Yes, No, Refused };
std::string_view writes_stick_name(WritesStick w) noexcept;

struct TableModel {
    std::vector<AddressRange> ranges;           // valid addresses: sorted, disjoint, not adjacent
    std::uint16_t max_quantity = 0;             // most items one read was seen to take (0: unknown)
    WritesStick writes = WritesStick::Unknown;  // coils and holding registers only
    // Of `ranges`, those refinement found during the run (the learning sweep stepped over them).
    std::vector<AddressRange> found_during_run;

    bool contains(std::uint32_t address) const noexcept;
    // The range holding `address`, or null.
    const AddressRange* range_of(std::uint32_t address) const noexcept;
    std::uint32_t entries() const noexcept;
};

inline constexpr std::size_t kTableCount = 4;
std::string_view table_label(codec::Table t) noexcept;  // "coils", "holding-registers", ...

struct DeviceModel {
    std::string source;  // "learned", "--map", or the file it was read from
    std::array<TableModel, kTableCount> tables{};
    std::vector<std::uint8_t> units;  // unit ids seen answering (empty: not asked)
    // What an exception costs the target, in ms of extra delay, by exception code (index 1..4):
    // libmodbus sleeps its response timeout and flushes after 01 and 03, not after 02.
    std::array<std::uint32_t, 5> exception_pause_ms{};
    bool partial = false;  // learning ran out of its time budget

    TableModel& table(codec::Table t) noexcept { return tables[static_cast<std::size_t>(t)]; }
    const TableModel& table(codec::Table t) const noexcept {
        return tables[static_cast<std::size_t>(t)];
    }
    bool empty() const noexcept;  // no table has a known address
    // True when any exception but 02 makes the target pause: cases owed one are rationed.
    bool pauses_after_exceptions() const noexcept;
};

// The addresses just outside each of a table's ranges (the one before its first, the one past
// its last) that no other range holds: learning refused each of them alone, so a read of one
// owes exception 02.
std::vector<std::uint16_t> refused_neighbours(const TableModel& table);

// A read of one item at the first address of the map, from the first table (holding
// registers, input registers, coils, discrete inputs) the model knows and whose read the
// target supports: a liveness probe the target answers normally. Nothing when there is none.
std::optional<std::vector<std::uint8_t>> probe_in_map(const DeviceModel& model,
                                                      const std::array<bool, 256>& unsupported);

// Sorts and merges adjacent or overlapping ranges.
void normalise(std::vector<AddressRange>& ranges);

// --map: comma-separated TABLE=FIRST-LAST or TABLE=ADDRESS entries (a table may repeat), TABLE
// one of coils, discrete-inputs (discrete), input-registers (input), holding-registers
// (holding); decimal or 0x hex protocol addresses. An InvalidInput error on a bad entry.
Result<DeviceModel> parse_map(const std::string& text);

// The model as JSON (an object; see docs/fuzz.md) and back (InvalidInput when it is not one).
std::string model_to_json(const DeviceModel& m);
Result<DeviceModel> model_from_json(const std::string& text);
// --device-model FILE: NotFound when there is no such file.
Result<DeviceModel> load_model(const std::string& path);

// Lines for the summary: one per table, then units and pauses.
std::string format_model(const DeviceModel& m);

struct LearnOptions {
    int timeout_ms = 1000;
    std::int64_t budget_ns = 0;        // 0: no bound; else learning stops (partial) after this long
    std::uint32_t stride = 16;         // sweep step: ranges shorter than this may be missed
    std::vector<std::uint16_t> hints;  // addresses to try first (--dict words)
    // Brings back a target that died while learning and did not come back at once: the
    // campaign's --target-cmd or --restart-cmd (true: it is back). Empty: only a supervisor
    // (systemd, a watchdog) brings it back, so learning waits a little for one.
    std::function<bool()> restart;
};

struct LearnStats {
    std::uint64_t requests = 0;
    double seconds = 0;
    // Requests after which the target answered nothing more (it closed, died or hung): the
    // campaign looks at each alone before anything else.
    std::vector<std::vector<std::uint8_t>> stream_killers;
};

// Learns the model by asking: the unit ids that answer, every table's valid ranges (a sweep,
// then each edge found exactly), the largest read accepted, whether writes stick (a read, a
// write of another value, a read back, the old value restored), and what an exception costs.
DeviceModel learn_device_model(Connector& target, const TargetProfile& profile,
                               const LearnOptions& options, LearnStats* stats = nullptr);

// How far refinement has gone through the addresses the learning sweep stepped over.
struct RefineCursor {
    std::array<std::uint32_t, kTableCount> next{};  // per table, the next of its unswept addresses
    bool done = false;                              // every table's unswept address asked
    // The model is partial (learning ran out of time before it swept every table): the swept
    // addresses are asked too, first.
    bool swept_too = false;
};

// Refines a learned model during the run: reads of one item at the addresses the learning sweep
// (options.stride) stepped over, its gaps halved in turn across the whole table (the middle of
// every gap first, then the quarters, ...), so a short range anywhere is found early. At most
// `max_requests` reads, then it returns (the cursor keeps its place). Around an address that
// answers, the addresses are asked outwards until one is refused on each side; the ranges found
// join the model (in `found_during_run` too), and a table that had none has its largest read
// and its writes learned. A partial model (learning ran out of time) is completed this way.
// True when the model changed.
bool refine_device_model(Connector& target, const TargetProfile& profile,
                         const LearnOptions& options, DeviceModel& model, RefineCursor& cursor,
                         std::uint32_t max_requests, LearnStats& stats);

}  // namespace mbstorm::netfuzz
