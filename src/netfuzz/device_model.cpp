#include "netfuzz/device_model.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "codec/address.hpp"
#include "codec/exception_code.hpp"
#include "codec/function_code.hpp"
#include "codec/limits.hpp"
#include "codec/mbap.hpp"
#include "net/clock.hpp"
#include "netfuzz/ask.hpp"
#include "netfuzz/executor.hpp"

namespace mbstorm::netfuzz {
namespace {

namespace lim = codec::limits;
using Pdu = std::vector<std::uint8_t>;
using codec::Table;

constexpr std::array<Table, kTableCount> kTables = {Table::Coils, Table::DiscreteInputs,
                                                    Table::InputRegisters, Table::HoldingRegisters};

// The read function code of each table (the codec's table) and the most items one read may
// take (v1.1b3).
std::uint8_t read_function(Table t) noexcept {
    return codec::function_for(t, codec::RequestShape::AddressQuantity);
}

std::uint16_t spec_max_read(Table t) noexcept {
    const bool bits = t == Table::Coils || t == Table::DiscreteInputs;
    return bits ? lim::kMaxReadBits : lim::kMaxReadRegisters;
}

Pdu pdu5(std::uint8_t fc, std::uint16_t a, std::uint16_t b) {
    Pdu p{fc, 0, 0, 0, 0};
    codec::store_be16(p.data() + 1, a);
    codec::store_be16(p.data() + 3, b);
    return p;
}

bool table_from_name(const std::string& name, Table& out) {
    static const std::pair<const char*, Table> names[] = {
        {"coils", Table::Coils},
        {"discrete-inputs", Table::DiscreteInputs},
        {"discrete", Table::DiscreteInputs},
        {"input-registers", Table::InputRegisters},
        {"input", Table::InputRegisters},
        {"holding-registers", Table::HoldingRegisters},
        {"holding", Table::HoldingRegisters}};
    for (const auto& [n, t] : names)
        if (name == n) {
            out = t;
            return true;
        }
    return false;
}

}  // namespace

std::string_view writes_stick_name(WritesStick w) noexcept {
    switch (w) {
        case WritesStick::Unknown:
            return "unknown";
        case WritesStick::Yes:
            return "yes";
        case WritesStick::No:
            return "no";
        case WritesStick::Refused:
            return "refused";
    }
    return "unknown";
}

std::string_view table_label(Table t) noexcept {
    switch (t) {
        case Table::Coils:
            return "coils";
        case Table::DiscreteInputs:
            return "discrete-inputs";
        case Table::InputRegisters:
            return "input-registers";
        case Table::HoldingRegisters:
            return "holding-registers";
    }
    return "?";
}

bool TableModel::contains(std::uint32_t address) const noexcept {
    return range_of(address) != nullptr;
}

const AddressRange* TableModel::range_of(std::uint32_t address) const noexcept {
    for (const AddressRange& r : ranges)
        if (address >= r.first && address <= r.last) return &r;
    return nullptr;
}

std::uint32_t TableModel::entries() const noexcept {
    std::uint32_t n = 0;
    for (const AddressRange& r : ranges) n += r.size();
    return n;
}

bool DeviceModel::empty() const noexcept {
    return std::all_of(tables.begin(), tables.end(),
                       [](const TableModel& t) { return t.ranges.empty(); });
}

bool DeviceModel::pauses_after_exceptions() const noexcept {
    return exception_pause_ms[1] > 0 || exception_pause_ms[3] > 0 || exception_pause_ms[4] > 0;
}

std::vector<std::uint16_t> refused_neighbours(const TableModel& table) {
    std::vector<std::uint16_t> out;
    for (const AddressRange& r : table.ranges) {
        if (r.first > 0 && !table.contains(r.first - 1u)) out.push_back(r.first - 1);
        if (r.last < 0xFFFF && !table.contains(r.last + 1u)) out.push_back(r.last + 1);
    }
    return out;
}

std::optional<std::vector<std::uint8_t>> probe_in_map(const DeviceModel& model,
                                                      const std::array<bool, 256>& unsupported) {
    using codec::Table;
    for (const Table table :
         {Table::HoldingRegisters, Table::InputRegisters, Table::Coils, Table::DiscreteInputs}) {
        const std::uint8_t fc = codec::function_for(table, codec::RequestShape::AddressQuantity);
        const TableModel& tm = model.table(table);
        if (tm.ranges.empty() || unsupported[fc]) continue;
        const std::uint16_t at = tm.ranges.front().first;
        return std::vector<std::uint8_t>{fc, static_cast<std::uint8_t>(at >> 8),
                                         static_cast<std::uint8_t>(at), 0, 1};
    }
    return std::nullopt;
}

void normalise(std::vector<AddressRange>& ranges) {
    std::sort(ranges.begin(), ranges.end(),
              [](const AddressRange& a, const AddressRange& b) { return a.first < b.first; });
    std::vector<AddressRange> out;
    for (const AddressRange& r : ranges) {
        if (!out.empty() && std::uint32_t{r.first} <= std::uint32_t{out.back().last} + 1)
            out.back().last = std::max(out.back().last, r.last);
        else
            out.push_back(r);
    }
    ranges = std::move(out);
}

Result<DeviceModel> parse_map(const std::string& text) {
    DeviceModel out;
    out.source = "--map";
    std::stringstream in(text);
    std::string entry;
    while (std::getline(in, entry, ',')) {
        const auto eq = entry.find('=');
        Table t{};
        if (eq == std::string::npos || !table_from_name(entry.substr(0, eq), t)) {
            return Error(ErrorCode::InvalidInput,
                         fmt::format("--map entry '{}': expected TABLE=FIRST-LAST, TABLE one of "
                                     "coils, discrete, input, holding (e.g. "
                                     "holding=1000-1099,coils=200-263)",
                                     entry));
        }
        // The project's address rule: protocol addresses, or reference numbers of the table
        // (holding=40001-40100) as a vendor's manual lists them.
        codec::AddressRange parsed;
        if (std::string why = codec::parse_address_range(entry.substr(eq + 1), t, parsed);
            !why.empty() || parsed.last < parsed.first) {
            return Error(ErrorCode::InvalidInput,
                         fmt::format("--map entry '{}': {}", entry,
                                     why.empty() ? "FIRST must not be above LAST" : why));
        }
        const AddressRange r{parsed.first, parsed.last};
        out.table(t).ranges.push_back(r);
    }
    for (TableModel& t : out.tables) normalise(t.ranges);
    if (out.empty()) {
        return Error(ErrorCode::InvalidInput,
                     "--map: no table given (e.g. holding=1000-1099,coils=200-263)");
    }
    return out;
}

std::string model_to_json(const DeviceModel& m) {
    using nlohmann::json;
    json tables = json::object();
    for (Table t : kTables) {
        const TableModel& tm = m.table(t);
        json ranges = json::array();
        for (const AddressRange& r : tm.ranges) ranges.push_back({r.first, r.last});
        json found = json::array();
        for (const AddressRange& r : tm.found_during_run) found.push_back({r.first, r.last});
        tables[std::string(table_label(t))] = {{"ranges", ranges},
                                               {"found_during_run", found},
                                               {"entries", tm.entries()},
                                               {"max_quantity", tm.max_quantity},
                                               {"writes_stick", writes_stick_name(tm.writes)}};
    }
    json pauses = json::object();
    for (std::size_t code = 1; code < m.exception_pause_ms.size(); ++code)
        pauses[fmt::format("{:02X}", code)] = m.exception_pause_ms[code];
    const json j = {{"source", m.source},
                    {"tables", tables},
                    {"units", m.units},
                    {"exception_pause_ms", pauses},
                    {"partial", m.partial}};
    return j.dump(2) + "\n";
}

namespace {
// A JSON value that must be a whole number in 0..max: anything else (a fraction, a negative
// number, 3e28: converting those is undefined behaviour) is refused with `what` named.
std::uint64_t whole_number(const nlohmann::json& v, std::uint64_t max, std::string_view what) {
    if (!v.is_number_unsigned() || v.get<std::uint64_t>() > max)
        throw std::runtime_error(
            fmt::format("{} must be a whole number 0..{}, not {}", what, max, v.dump()));
    return v.get<std::uint64_t>();
}

// A list of [first, last] pairs, sorted and merged.
bool ranges_from_json(const nlohmann::json& list, const std::string& table,
                      std::vector<AddressRange>& out, std::string& error) {
    for (const auto& r : list) {
        const auto first = whole_number(r.at(0), 0xFFFF, "a range's first address"),
                   last = whole_number(r.at(1), 0xFFFF, "a range's last address");
        if (first > last) {
            error = fmt::format("{}: range {}-{} is not within 0..65535", table, first, last);
            return false;
        }
        out.push_back(
            AddressRange{static_cast<std::uint16_t>(first), static_cast<std::uint16_t>(last)});
    }
    normalise(out);
    return true;
}

// The model in `text`; false with `error`. nlohmann's exceptions and whole_number's stay
// inside: model_from_json returns the Error.
bool read_model(const std::string& text, DeviceModel& out, std::string& error) {
    using nlohmann::json;
    out = DeviceModel{};
    const json j = json::parse(text, nullptr, false);
    if (j.is_discarded() || !j.is_object() || !j.contains("tables") || !j["tables"].is_object()) {
        error = "not a device model (a JSON object with \"tables\", as fuzz writes model.json)";
        return false;
    }
    try {
        for (const auto& [name, tj] : j["tables"].items()) {
            Table t{};
            if (!table_from_name(name, t)) {
                error = fmt::format("unknown table '{}'", name);
                return false;
            }
            TableModel& tm = out.table(t);
            if (!ranges_from_json(tj.at("ranges"), name, tm.ranges, error)) return false;
            if (tj.contains("found_during_run") &&
                !ranges_from_json(tj["found_during_run"], name, tm.found_during_run, error))
                return false;
            if (tj.contains("max_quantity"))
                tm.max_quantity = static_cast<std::uint16_t>(
                    whole_number(tj["max_quantity"], 0xFFFF, "max_quantity"));
            const std::string w = tj.value("writes_stick", std::string("unknown"));
            for (WritesStick ws : {WritesStick::Yes, WritesStick::No, WritesStick::Refused})
                if (w == writes_stick_name(ws)) tm.writes = ws;
        }
        out.partial = j.value("partial", false);
        if (j.contains("units"))
            for (const auto& u : j["units"])
                out.units.push_back(static_cast<std::uint8_t>(whole_number(u, 0xFF, "a unit id")));
        if (j.contains("exception_pause_ms"))
            for (const auto& [code, ms] : j["exception_pause_ms"].items()) {
                const unsigned long c = std::stoul(code, nullptr, 16);
                if (c >= 1 && c < out.exception_pause_ms.size())
                    out.exception_pause_ms[c] = static_cast<std::uint32_t>(
                        whole_number(ms, 0xFFFFFFFF, "an exception pause"));
            }
    } catch (const std::exception& e) {
        error = fmt::format("bad device model: {}", e.what());
        return false;
    }
    return true;
}

}  // namespace

Result<DeviceModel> model_from_json(const std::string& text) {
    DeviceModel model;
    if (std::string error; !read_model(text, model, error))
        return Error(ErrorCode::InvalidInput, std::move(error));
    return model;
}

Result<DeviceModel> load_model(const std::string& path) {
    std::ifstream in(path);
    if (!in)
        return Error(open_failure(path), fmt::format("--device-model {}: cannot read it", path));
    std::stringstream text;
    text << in.rdbuf();
    Result<DeviceModel> model = model_from_json(text.str());
    if (!model.ok()) return std::move(model).error().prefixed("--device-model " + path);
    model->source = path;
    return model;
}

std::string format_model(const DeviceModel& m) {
    std::string s = fmt::format("Device model ({}{})\n", m.source, m.partial ? ", partial" : "");
    for (Table t : kTables) {
        const TableModel& tm = m.table(t);
        std::string ranges;
        for (const AddressRange& r : tm.ranges)
            ranges += fmt::format("{}{}", ranges.empty() ? "" : ", ",
                                  r.first == r.last ? fmt::format("{}", r.first)
                                                    : fmt::format("{}-{}", r.first, r.last));
        if (ranges.empty()) ranges = "none";
        s += fmt::format("  {:<18} {} ({} entries)", table_label(t), ranges, tm.entries());
        if (!tm.found_during_run.empty())
            s += fmt::format(", {} range{} found during the run", tm.found_during_run.size(),
                             tm.found_during_run.size() == 1 ? "" : "s");
        if (tm.max_quantity) s += fmt::format(", reads up to {}", tm.max_quantity);
        if (tm.writes != WritesStick::Unknown)
            s += fmt::format(", writes stick: {}", writes_stick_name(tm.writes));
        s += "\n";
    }
    if (!m.units.empty()) {
        std::string units;
        for (std::size_t i = 0; i < m.units.size() && i < 12; ++i)
            units += fmt::format("{}{}", i ? ", " : "", m.units[i]);
        if (m.units.size() > 12) units += fmt::format(" ... ({} in all)", m.units.size());
        s += fmt::format("  units answering    {}\n", units);
    }
    std::string pauses;
    for (std::size_t code = 1; code < m.exception_pause_ms.size(); ++code)
        if (m.exception_pause_ms[code])
            pauses += fmt::format("{}{:02X}: {} ms", pauses.empty() ? "" : ", ", code,
                                  m.exception_pause_ms[code]);
    s += fmt::format("  exception pauses   {}\n", pauses.empty() ? "none" : pauses);
    return s;
}

namespace {

// Asks the target many requests, pipelined in chunks; requests an exception made the target
// drop are asked again, behind it.
std::uint8_t exception_of(const Pdu& a) {
    return a.size() == 2 && (a[0] & codec::kExceptionBit) ? a[1] : 0;
}

class Asker {
  public:
    Asker(Connector& target, const TargetProfile& profile, const LearnOptions& o,
          std::int64_t deadline, LearnStats& stats)
        : target_(target), profile_(profile), options_(o), deadline_(deadline), stats_(stats) {}

    bool out_of_time() const { return deadline_ && net::now_ns() >= deadline_; }
    std::vector<Pdu> ask(const std::vector<Pdu>& pdus, std::uint8_t unit);
    std::vector<Pdu> ask(const std::vector<Pdu>& pdus) { return ask(pdus, profile_.unit); }
    // One pass: every request asked once (pipelined where the framing allows).
    std::vector<Pdu> ask_once(const std::vector<Pdu>& pdus, std::uint8_t unit);
    bool killed_stream(const Pdu& pdu) const;
    // One request; a silence is asked again (twice at most) once the target has answered a
    // request with an exception (it refuses what it does not hold, so a silence is a drop) or
    // answered a silence when asked again: a boundary or a hole learned from a drop is wrong.
    Pdu ask_one(const Pdu& pdu) {
        Pdu answer = ask(std::vector<Pdu>{pdu}).front();
        for (int again = 0;
             again < 2 && answer.empty() && (refuses_ || drops_seen_) && !out_of_time(); ++again)
            answer = ask(std::vector<Pdu>{pdu}).front();
        return answer;
    }
    // Round trip of one request on a fresh connection, in ms (the answer in `answer`).
    double timed(const Pdu& pdu, Pdu& answer);
    const TargetProfile& profile() const { return profile_; }

  private:
    // After a stream died: whether the target answers again (a supervisor may restart it).
    bool came_back();
    static constexpr unsigned kMaxLearnDeaths = 8;
    unsigned deaths_ = 0;
    bool refuses_ = false;     // some request was answered with an exception
    bool drops_seen_ = false;  // a silence was answered when asked again
    Connector& target_;
    const TargetProfile& profile_;
    const LearnOptions& options_;
    std::int64_t deadline_;
    LearnStats& stats_;
};

// A device behind a lossy link or a busy gateway drops requests now and then: the silences are
// asked again (kMaxAskAgain rounds at most; a round that gets no answer ends it, unless an
// earlier silence was answered when asked again) before one is taken for an address outside
// the map (else the map is learned full of holes). Not when most requests went unanswered:
// that target is silent on purpose (to what is not in its map, or to a unit it is not), and
// asking again costs a timeout for nothing. Requests that killed the stream are not asked
// again.
constexpr int kMaxAskAgain = 8;

std::vector<Pdu> Asker::ask(const std::vector<Pdu>& pdus, std::uint8_t unit) {
    std::vector<Pdu> answers = ask_once(pdus, unit);
    for (int round = 0; round < kMaxAskAgain && !out_of_time(); ++round) {
        std::vector<std::size_t> silent;
        for (std::size_t i = 0; i < pdus.size(); ++i)
            if (answers[i].empty() && !killed_stream(pdus[i])) silent.push_back(i);
        if (silent.empty() || silent.size() * 2 > pdus.size()) break;
        std::vector<Pdu> again;
        for (const std::size_t i : silent) again.push_back(pdus[i]);
        std::vector<Pdu> got = ask_once(again, unit);
        bool progress = false;
        for (std::size_t k = 0; k < silent.size(); ++k) {
            if (got[k].empty()) continue;
            answers[silent[k]] = std::move(got[k]);
            progress = drops_seen_ = true;
        }
        // Silent on purpose after all; unless silences were drops before (a round may lose
        // the last few again).
        if (!progress && !drops_seen_) break;
    }
    return answers;
}

bool Asker::killed_stream(const Pdu& pdu) const {
    return std::find(stats_.stream_killers.begin(), stats_.stream_killers.end(), pdu) !=
           stats_.stream_killers.end();
}

std::vector<Pdu> Asker::ask_once(const std::vector<Pdu>& pdus, std::uint8_t unit) {
    std::vector<Pdu> answers(pdus.size());
    const std::size_t chunk = profile_.framing == codec::Framing::Mbap ? 256 : 1;
    std::size_t next = 0;
    // After the stream died in a pipelined chunk, its requests go one at a time until past
    // the one that did it (a server may die before sending the answers it had made).
    std::size_t careful_until = 0;
    while (next < pdus.size() && !out_of_time()) {
        const std::size_t n = std::min(next < careful_until ? 1 : chunk, pdus.size() - next);
        std::vector<Pdu> frames;
        for (std::size_t i = 0; i < n; ++i)
            frames.push_back(
                frame_pdu(pdus[next + i], static_cast<std::uint16_t>(i), unit, profile_.framing));
        bool connected = false;
        std::vector<Pdu> got = ask_pipelined(target_, frames, options_.timeout_ms, connected);
        stats_.requests += n;
        if (!connected && !came_back()) break;
        if (!connected) continue;
        std::size_t settled = n;
        for (std::size_t i = 0; i + 1 < n; ++i) {
            // A target that drops what follows an exception is asked the rest again.
            const bool exception = got[i].size() == 2 && (got[i][0] & codec::kExceptionBit);
            if (exception && got[i + 1].empty()) {
                settled = i + 1;
                break;
            }
            // Nothing answered from here on: the stream died at this request (learning may
            // crash a target too). It is kept for the campaign to look at first; the rest is
            // asked again once the target is back.
            if (got[i].empty() && std::all_of(got.begin() + static_cast<std::ptrdiff_t>(i),
                                              got.end(), [](const Pdu& a) { return a.empty(); })) {
                settled = i;
                careful_until = next + n;
                if (!came_back()) settled = n;
                break;
            }
        }
        // One request alone and no answer, not even on the probe after it (asked twice: a
        // target that drops requests may drop a probe): it killed the stream.
        if (n == 1 && got[0].empty() &&
            probe_target(target_, profile_, options_.timeout_ms) != ProbeResult::Ok &&
            probe_target(target_, profile_, options_.timeout_ms) != ProbeResult::Ok) {
            stats_.stream_killers.push_back(pdus[next]);
            if (!came_back()) break;
        }
        for (std::size_t i = 0; i < settled; ++i) {
            refuses_ = refuses_ || exception_of(got[i]) != 0;
            answers[next + i] = std::move(got[i]);
        }
        next += settled;
    }
    return answers;
}

bool Asker::came_back() {
    if (++deaths_ > kMaxLearnDeaths) return false;
    // Whoever started the target starts it again: waiting for a supervisor would be in vain.
    if (options_.restart)
        return probe_target(target_, profile_, options_.timeout_ms) == ProbeResult::Ok ||
               options_.restart();
    for (int wait_ms = 20; wait_ms < 2000 && !out_of_time(); wait_ms *= 2) {
        if (probe_target(target_, profile_, options_.timeout_ms) == ProbeResult::Ok) return true;
        ::usleep(static_cast<useconds_t>(wait_ms) * 1000);
    }
    return false;
}

double Asker::timed(const Pdu& pdu, Pdu& answer) {
    const std::int64_t t0 = net::now_ns();
    answer = ask(std::vector<Pdu>{pdu}).front();  // once: a retry's timeouts are no pause
    return static_cast<double>(net::now_ns() - t0) / 1e6;
}

bool normal_answer(const Pdu& a, std::uint8_t fc) {
    return !a.empty() && a[0] == fc;
}

// Where vendors start their maps: the sweep asks each and the one after it.
constexpr std::array<std::uint32_t, 12> kVendorBases = {0,    100,   1000,  2000,  3000,  4000,
                                                        5000, 10000, 20000, 30000, 40000, 50000};
// Small devices keep their few registers low: the sweep asks the first 1,024 addresses four
// times as densely (256 requests more), so a range of 4 there is found.
constexpr std::uint32_t kDenseBelow = 1024;

// Whether the learning sweep asks `address` (hints aside).
bool swept(std::uint32_t address, std::uint32_t stride) {
    stride = std::max<std::uint32_t>(1, stride);
    if (address % stride == 0 || address == 0xFFFF) return true;
    if (address < kDenseBelow && address % std::max<std::uint32_t>(1, stride / 4) == 0) return true;
    return std::any_of(kVendorBases.begin(), kVendorBases.end(),
                       [&](std::uint32_t b) { return address == b || address == b + 1; });
}

// Addresses a sweep asks: the user's, then the swept ones.
std::vector<std::uint32_t> sample_addresses(const LearnOptions& o) {
    std::set<std::uint32_t> s(o.hints.begin(), o.hints.end());
    for (std::uint32_t a = 0; a < 0x10000; ++a)
        if (swept(a, o.stride)) s.insert(a);
    return {s.begin(), s.end()};
}

// Which of `addresses` a read of one item at each answers normally.
std::vector<bool> readable(Asker& asker, std::uint8_t fc, const std::vector<std::uint32_t>& addrs) {
    std::vector<Pdu> pdus;
    for (std::uint32_t a : addrs) pdus.push_back(pdu5(fc, static_cast<std::uint16_t>(a), 1));
    const std::vector<Pdu> got = asker.ask(pdus);
    std::vector<bool> ok(addrs.size());
    for (std::size_t i = 0; i < addrs.size(); ++i) ok[i] = normal_answer(got[i], fc);
    return ok;
}

// The table's valid ranges: a sweep, then every address between a readable sample and an
// unreadable neighbour, so that each edge is exact.
std::vector<AddressRange> learn_ranges(Asker& asker, std::uint8_t fc, const LearnOptions& o) {
    std::vector<std::uint32_t> addrs = sample_addresses(o);
    std::vector<bool> ok = readable(asker, fc, addrs);
    std::vector<std::uint32_t> edges;
    for (std::size_t i = 0; i + 1 < addrs.size(); ++i)
        if (ok[i] != ok[i + 1])
            for (std::uint32_t a = addrs[i] + 1; a < addrs[i + 1]; ++a) edges.push_back(a);
    const std::vector<bool> edge_ok = readable(asker, fc, edges);
    std::vector<std::pair<std::uint32_t, bool>> all;
    for (std::size_t i = 0; i < addrs.size(); ++i) all.emplace_back(addrs[i], ok[i]);
    for (std::size_t i = 0; i < edges.size(); ++i) all.emplace_back(edges[i], edge_ok[i]);
    std::sort(all.begin(), all.end());
    std::vector<AddressRange> ranges;
    bool open = false;
    for (const auto& [a, good] : all) {
        if (good && !open) ranges.push_back(AddressRange{static_cast<std::uint16_t>(a), 0});
        if (good) ranges.back().last = static_cast<std::uint16_t>(a);
        open = good;
    }
    normalise(ranges);
    return ranges;
}

// The most items one read at the start of the largest range takes: all it can hold, else a
// binary search (each refusal may cost the target's pause, so only where needed).
std::uint16_t learn_max_quantity(Asker& asker, Table t, const TableModel& tm) {
    const auto largest = std::max_element(
        tm.ranges.begin(), tm.ranges.end(),
        [](const AddressRange& a, const AddressRange& b) { return a.size() < b.size(); });
    if (largest == tm.ranges.end()) return 0;
    const std::uint8_t fc = read_function(t);
    std::uint32_t good = 1, bad = std::min<std::uint32_t>(largest->size(), spec_max_read(t));
    if (normal_answer(asker.ask_one(pdu5(fc, largest->first, static_cast<std::uint16_t>(bad))), fc))
        return static_cast<std::uint16_t>(bad);
    while (bad - good > 1 && !asker.out_of_time()) {
        const std::uint32_t mid = (good + bad) / 2;
        const bool ok = normal_answer(
            asker.ask_one(pdu5(fc, largest->first, static_cast<std::uint16_t>(mid))), fc);
        (ok ? good : bad) = mid;
    }
    return static_cast<std::uint16_t>(good);
}

// Reads one item, writes another value, reads it back, restores the first.
WritesStick learn_writes(Asker& asker, Table t, const TableModel& tm) {
    if (tm.ranges.empty()) return WritesStick::Unknown;
    const bool coils = t == Table::Coils;
    const std::uint8_t read_fc = read_function(t);
    const std::uint8_t write_fc = codec::function_for(
        t, coils ? codec::RequestShape::SingleCoil : codec::RequestShape::SingleRegister);
    if (asker.profile().unsupported[write_fc]) return WritesStick::Refused;
    const std::uint16_t at = tm.ranges.front().first;
    const Pdu before = asker.ask_one(pdu5(read_fc, at, 1));
    if (!normal_answer(before, read_fc) || before.size() < 3) return WritesStick::Unknown;
    std::uint16_t old = 0, fresh = 0;
    if (coils) {
        old = before[2] & 1 ? 0xFF00 : 0x0000;
        fresh = old ? 0x0000 : 0xFF00;
    } else {
        if (before.size() < 4) return WritesStick::Unknown;
        old = codec::load_be16(before.data() + 2);
        fresh = static_cast<std::uint16_t>(old ^ 0x5A5A);
    }
    const Pdu written = asker.ask_one(pdu5(write_fc, at, fresh));
    if (!normal_answer(written, write_fc))
        return exception_of(written) ? WritesStick::Refused : WritesStick::Unknown;
    const Pdu after = asker.ask_one(pdu5(read_fc, at, 1));
    asker.ask_one(pdu5(write_fc, at, old));
    if (!normal_answer(after, read_fc) || after.size() < 3) return WritesStick::Unknown;
    const std::uint16_t got = coils ? (after[2] & 1 ? 0xFF00 : 0x0000)
                                    : (after.size() >= 4 ? codec::load_be16(after.data() + 2) : 0);
    return got == fresh ? WritesStick::Yes : WritesStick::No;
}

void learn_units(Connector& target, const TargetProfile& p, int timeout_ms, DeviceModel& m,
                 LearnStats& st) {
    if (p.framing != codec::Framing::Mbap) {
        m.units = {p.unit};
        return;
    }
    // All 256 at once: a unit the target ignores costs one timeout for all of them.
    std::vector<Pdu> frames;
    for (unsigned u = 0; u < 256; ++u)
        frames.push_back(frame_pdu(p.probe_pdu, static_cast<std::uint16_t>(u),
                                   static_cast<std::uint8_t>(u), p.framing));
    bool connected = false;
    std::vector<Pdu> got = ask_pipelined(target, frames, timeout_ms, connected);
    st.requests += frames.size();
    // A target that answers most units and not a few may have dropped those (a lossy link):
    // they are asked again while each round gets answers.
    for (int round = 0; round < kMaxAskAgain; ++round) {
        std::vector<unsigned> silent;
        for (unsigned u = 0; u < 256; ++u)
            if (got[u].empty()) silent.push_back(u);
        if (silent.empty() || silent.size() * 2 > 256) break;
        std::vector<Pdu> again;
        for (const unsigned u : silent)  // each with its place as its transaction id (ask.hpp)
            again.push_back(frame_pdu(p.probe_pdu, static_cast<std::uint16_t>(again.size()),
                                      static_cast<std::uint8_t>(u), p.framing));
        const std::vector<Pdu> more = ask_pipelined(target, again, timeout_ms, connected);
        st.requests += again.size();
        bool progress = false;
        for (std::size_t k = 0; k < silent.size(); ++k) {
            if (more[k].empty()) continue;
            got[silent[k]] = more[k];
            progress = true;
        }
        if (!progress) break;
    }
    for (unsigned u = 0; u < 256; ++u)
        if (!got[u].empty()) m.units.push_back(static_cast<std::uint8_t>(u));
}

// A request owed exception `code` (from what the model knows), if one can be made.
bool request_owing(const DeviceModel& m, std::uint8_t code, Pdu& out) {
    for (Table t : kTables) {
        const TableModel& tm = m.table(t);
        if (tm.ranges.empty()) continue;
        const std::uint8_t fc = read_function(t);
        if (code == 3) {
            out = pdu5(fc, tm.ranges.front().first, 0);
            return true;
        }
        if (code == 2 && tm.entries() < 0x10000) {
            const std::uint32_t past = tm.ranges.back().last + 1u;
            const std::uint16_t at = past <= 0xFFFF
                                         ? static_cast<std::uint16_t>(past)
                                         : static_cast<std::uint16_t>(tm.ranges.front().first - 1);
            out = pdu5(fc, at, 1);
            return true;
        }
    }
    return false;
}

// What each exception costs: its round trip and the next request's, against two normal ones.
void learn_pauses(Asker& asker, DeviceModel& m, std::uint8_t unsupported_fc) {
    Pdu answer;
    // A read inside the map: the discovery probe may itself be answered with 02.
    Pdu probe = asker.profile().probe_pdu;
    for (Table t : kTables)
        if (!m.table(t).ranges.empty()) {
            probe = pdu5(read_function(t), m.table(t).ranges.front().first, 1);
            break;
        }
    double normal = asker.timed(probe, answer);
    normal = std::min(normal, asker.timed(probe, answer));
    for (std::uint8_t code : {std::uint8_t{1}, std::uint8_t{2}, std::uint8_t{3}}) {
        Pdu rq;
        if (code == 1) {
            if (!unsupported_fc) continue;
            rq = Pdu{unsupported_fc};
        } else if (!request_owing(m, code, rq)) {
            continue;
        }
        const double t = asker.timed(rq, answer) + asker.timed(probe, answer);
        const double extra = t - 2 * normal;
        if (exception_of(answer) == 0 && extra > 20)  // the probe itself was answered
            m.exception_pause_ms[code] = static_cast<std::uint32_t>(extra);
        if (asker.out_of_time()) return;
    }
}

}  // namespace

DeviceModel learn_device_model(Connector& target, const TargetProfile& profile,
                               const LearnOptions& options, LearnStats* stats) {
    LearnStats local;
    LearnStats& st = stats ? *stats : local;
    const std::int64_t t0 = net::now_ns();
    const std::int64_t deadline = options.budget_ns ? t0 + options.budget_ns : 0;
    Asker asker(target, profile, options, deadline, st);
    DeviceModel m;
    m.source = "learned";
    for (Table t : kTables) {
        const std::uint8_t fc = read_function(t);
        if (profile.unsupported[fc] || asker.out_of_time()) continue;
        m.table(t).ranges = learn_ranges(asker, fc, options);
    }
    for (Table t : kTables) {
        if (asker.out_of_time()) break;
        TableModel& tm = m.table(t);
        tm.max_quantity = learn_max_quantity(asker, t, tm);
        if (t == Table::Coils || t == Table::HoldingRegisters)
            tm.writes = learn_writes(asker, t, tm);
    }
    // A code the specification leaves to users (0x41..0x48): owed 01 unless the device has it.
    std::uint8_t unsupported_fc = 0;
    for (unsigned fc = 0x41; fc <= 0x48 && !unsupported_fc; ++fc)
        if (!profile.extended[fc]) unsupported_fc = static_cast<std::uint8_t>(fc);
    if (!asker.out_of_time()) learn_pauses(asker, m, unsupported_fc);
    if (!asker.out_of_time()) learn_units(target, profile, options.timeout_ms, m, st);
    m.partial = asker.out_of_time();
    st.seconds = static_cast<double>(net::now_ns() - t0) / 1e9;
    return m;
}

namespace {

// The offsets within a gap of the sweep in the order refinement asks them: the middle, then
// the quarters, the eighths, ... (16: 8, 4, 12, 2, 6, 10, 14, 1, 3, ...).
std::vector<std::uint32_t> gap_order(std::uint32_t stride, bool swept_too) {
    std::vector<std::uint32_t> order;
    if (swept_too) order.push_back(0);
    std::vector<bool> taken(stride);
    std::uint32_t step = 1;
    while (step * 2 < stride) step *= 2;
    for (; step >= 1; step /= 2)
        for (std::uint32_t o = step; o < stride; o += step)
            if (!taken[o]) {
                taken[o] = true;
                order.push_back(o);
            }
    return order;
}

// Up to `n` of the table's unswept addresses from the cursor on, none in the map: the same
// offset in every gap, then the next offset. The cursor moves past them.
std::vector<std::uint32_t> next_unswept(const TableModel& tm, std::uint32_t stride,
                                        const std::vector<std::uint32_t>& order, bool swept_too,
                                        std::uint32_t& cursor, std::uint32_t n) {
    const std::uint32_t gaps = (0x10000 + stride - 1) / stride;
    const std::uint32_t end = static_cast<std::uint32_t>(order.size()) * gaps;
    std::vector<std::uint32_t> out;
    for (; cursor < end && out.size() < n; ++cursor) {
        const std::uint32_t a = (cursor % gaps) * stride + order[cursor / gaps];
        if (a <= 0xFFFF && (swept_too || !swept(a, stride)) && !tm.contains(a)) out.push_back(a);
    }
    return out;
}

// The first address of the run of answering addresses that ends at `from`, asked a gap at a
// time towards `step` (-1: down, +1: up) until one is refused or the map or the table ends.
std::uint32_t answering_run_end(Asker& asker, std::uint8_t fc, std::uint32_t stride,
                                std::uint32_t from, int step, const TableModel& tm) {
    std::uint32_t end = from;
    for (;;) {
        std::vector<std::uint32_t> next;
        for (std::uint32_t a = end; next.size() < stride;) {
            if ((step < 0 && a == 0) || (step > 0 && a == 0xFFFF)) break;
            a = step < 0 ? a - 1 : a + 1;
            if (tm.contains(a)) break;
            next.push_back(a);
        }
        if (next.empty()) return end;
        const std::vector<bool> ok = readable(asker, fc, next);
        for (std::size_t i = 0; i < next.size(); ++i) {
            if (!ok[i]) return end;
            end = next[i];
        }
    }
}

// The range of answering addresses around `hit`, asked out from it until a refused address
// (or a known range) on each side, so that its edges are exact: a read just outside it owes
// 02. Nothing when `hit` does not answer again (a flaky answer).
std::optional<AddressRange> range_around(Asker& asker, std::uint8_t fc, std::uint32_t stride,
                                         std::uint32_t hit, const TableModel& tm) {
    if (!readable(asker, fc, {hit}).front()) return std::nullopt;
    const std::uint32_t first = answering_run_end(asker, fc, stride, hit, -1, tm);
    const std::uint32_t last = answering_run_end(asker, fc, stride, hit, +1, tm);
    return AddressRange{static_cast<std::uint16_t>(first), static_cast<std::uint16_t>(last)};
}

}  // namespace

bool refine_device_model(Connector& target, const TargetProfile& profile,
                         const LearnOptions& options, DeviceModel& model, RefineCursor& cursor,
                         std::uint32_t max_requests, LearnStats& stats) {
    const std::uint32_t stride = std::max<std::uint32_t>(1, options.stride);
    const std::vector<std::uint32_t> order = gap_order(stride, cursor.swept_too);
    const std::uint32_t end =
        static_cast<std::uint32_t>(order.size()) * ((0x10000 + stride - 1) / stride);
    const std::int64_t deadline = options.budget_ns ? net::now_ns() + options.budget_ns : 0;
    Asker asker(target, profile, options, deadline, stats);
    bool changed = false;
    cursor.done = true;
    for (Table t : kTables) {
        const std::size_t i = static_cast<std::size_t>(t);
        const std::uint8_t fc = read_function(t);
        if (profile.unsupported[fc]) continue;
        if (asker.out_of_time()) {
            cursor.done = false;
            continue;
        }
        TableModel& tm = model.table(t);
        const bool had_none = tm.ranges.empty();
        const std::vector<std::uint32_t> addrs = next_unswept(
            tm, stride, order, cursor.swept_too, cursor.next[i], max_requests / kTableCount);
        cursor.done = cursor.done && cursor.next[i] >= end;
        const std::vector<bool> ok = readable(asker, fc, addrs);
        for (std::size_t k = 0; k < addrs.size(); ++k) {
            if (!ok[k] || tm.contains(addrs[k])) continue;
            const std::optional<AddressRange> found = range_around(asker, fc, stride, addrs[k], tm);
            if (!found) continue;
            tm.ranges.push_back(*found);
            tm.found_during_run.push_back(*found);
            normalise(tm.ranges);
            normalise(tm.found_during_run);
            changed = true;
        }
        if (!had_none || tm.ranges.empty() || asker.out_of_time()) continue;
        tm.max_quantity = learn_max_quantity(asker, t, tm);
        if (t == Table::Coils || t == Table::HoldingRegisters)
            tm.writes = learn_writes(asker, t, tm);
    }
    return changed;
}

}  // namespace mbstorm::netfuzz
