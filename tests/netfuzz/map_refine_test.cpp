// Refining the learned map during the run: a device whose short ranges fall between the
// learning sweep's addresses (every 16th; every 4th below 1,024) has them found afterwards, by
// reads at the addresses the sweep stepped over, the middle of every gap first.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "codec/limits.hpp"
#include "codec/mbap.hpp"
#include "fuzz_test_support.hpp"
#include "net/socket.hpp"
#include "netfuzz/device_model.hpp"
#include "netfuzz/discovery.hpp"
#include "netfuzz/link.hpp"
#include "thread_slave.hpp"

namespace mbstorm::netfuzz {
namespace {

using mbstorm::test::send_bytes;
using mbstorm::test::SlaveBytes;
using mbstorm::test::ThreadSlave;

struct Span {
    std::uint32_t first, last;
};
// Holding 0-9 and 5000 (the sweep asks both), 6998-7002 (the middle of a gap: 7000); input
// 4099-4100 (a table learning found empty, whose largest read is learned once a range is found).
const std::vector<Span> kHolding = {{0, 9}, {5000, 5000}, {6998, 7002}};
const std::vector<Span> kInput = {{4099, 4100}};

bool inside(const std::vector<Span>& map, std::uint32_t address, std::uint32_t quantity) {
    for (const Span& s : map)
        if (address >= s.first && address + quantity - 1 <= s.last) return true;
    return false;
}

// The answer to one request PDU: reads of FC 03 and 04 inside the map, 02 for the other
// addresses and the other tables, 01 for every other function code.
SlaveBytes answer(const std::uint8_t* pdu, std::size_t size) {
    const std::uint8_t fc = pdu[0];
    if (fc < 1 || fc > 4) return {static_cast<std::uint8_t>(fc | 0x80), 0x01};
    if (size != 5) return {static_cast<std::uint8_t>(fc | 0x80), 0x03};
    const std::uint32_t address = codec::load_be16(pdu + 1), quantity = codec::load_be16(pdu + 3);
    const std::vector<Span>* map = fc == 3 ? &kHolding : fc == 4 ? &kInput : nullptr;
    if (quantity < 1 || quantity > 125) return {static_cast<std::uint8_t>(fc | 0x80), 0x03};
    if (!map || !inside(*map, address, quantity))
        return {static_cast<std::uint8_t>(fc | 0x80), 0x02};
    SlaveBytes out{fc, static_cast<std::uint8_t>(2 * quantity)};
    out.resize(2 + 2 * quantity, 0x11);
    return out;
}

void serve(int fd, SlaveBytes& buf) {
    while (buf.size() >= codec::limits::kMbapHeader + 1) {
        const std::size_t whole = codec::announced_adu_size(buf.data());
        if (whole <= codec::limits::kMbapHeader || whole > 260) {
            buf.clear();  // not Modbus: forget it
            return;
        }
        if (buf.size() < whole) return;
        const SlaveBytes pdu = answer(buf.data() + 7, whole - 7);
        SlaveBytes adu = {buf[0], buf[1], 0, 0, 0, static_cast<std::uint8_t>(pdu.size() + 1),
                          buf[6]};
        adu.insert(adu.end(), pdu.begin(), pdu.end());
        buf.erase(buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(whole));
        send_bytes(fd, adu);
    }
}

std::vector<AddressRange> ranges(std::initializer_list<std::pair<int, int>> list) {
    std::vector<AddressRange> out;
    for (auto [a, b] : list)
        out.push_back(AddressRange{static_cast<std::uint16_t>(a), static_cast<std::uint16_t>(b)});
    return out;
}

// The scripted device on a loopback port, discovered.
struct Device {
    ThreadSlave slave{serve};
    Result<net::Endpoint> endpoint = net::parse_endpoint(slave.endpoint(), 502);
    bool parsed = endpoint.ok();
    TcpConnector connector{parsed ? *endpoint : net::Endpoint{}};
    TargetProfile profile;
    Error error;
    bool discovered() {
        if (!parsed) return false;
        error = discover_target(connector, 1, 1000, profile);
        return error.ok();
    }
    // One turn of refinement: 512 reads per table.
    bool refine(DeviceModel& m, RefineCursor& cursor, LearnStats& st) {
        return refine_device_model(connector, profile, LearnOptions{}, m, cursor, 2048, st);
    }
};

TEST(MapRefine, RangesTheSweepSteppedOverAreFoundExactlyAndTheMiddleOfAGapFirst) {
    Device d;
    ASSERT_TRUE(d.discovered()) << d.error.text();
    LearnStats learned;
    DeviceModel m = learn_device_model(d.connector, d.profile, LearnOptions{}, &learned);
    ASSERT_EQ(m.table(codec::Table::HoldingRegisters).ranges, ranges({{0, 9}, {5000, 5000}}));
    ASSERT_TRUE(m.table(codec::Table::InputRegisters).ranges.empty());

    RefineCursor cursor;
    LearnStats st;
    // One turn of 4 x 512 reads reaches 7000, the 438th gap's middle.
    EXPECT_TRUE(d.refine(m, cursor, st));
    EXPECT_EQ(m.table(codec::Table::HoldingRegisters).ranges,
              ranges({{0, 9}, {5000, 5000}, {6998, 7002}}));
    EXPECT_EQ(m.table(codec::Table::HoldingRegisters).found_during_run, ranges({{6998, 7002}}));
    EXPECT_FALSE(cursor.done);
    int turns = 1;
    for (; !cursor.done && turns < 200; ++turns) d.refine(m, cursor, st);
    EXPECT_TRUE(cursor.done);
    EXPECT_EQ(m.table(codec::Table::InputRegisters).ranges, ranges({{4099, 4100}}));
    EXPECT_EQ(m.table(codec::Table::InputRegisters).found_during_run, ranges({{4099, 4100}}));
    EXPECT_EQ(m.table(codec::Table::InputRegisters).max_quantity, 2);
    EXPECT_EQ(m.table(codec::Table::HoldingRegisters).ranges,
              ranges({{0, 9}, {5000, 5000}, {6998, 7002}}));
    // At most every address but the sweep's every 16th, once per table, and the two gaps and
    // the largest read asked around the hits.
    EXPECT_LE(st.requests, 4u * (65536u - 4096u) + 64u);
    // Done means done: no read more.
    const std::uint64_t before = st.requests;
    EXPECT_FALSE(d.refine(m, cursor, st));
    EXPECT_EQ(st.requests, before);
}

// Learning ran out of time before it swept every table: refinement asks the swept addresses
// too, and completes the map exactly (a range spanning gaps is asked out to its edges).
TEST(MapRefine, APartialModelIsCompleted) {
    Device d;
    ASSERT_TRUE(d.discovered()) << d.error.text();
    DeviceModel m;
    m.partial = true;
    RefineCursor cursor;
    cursor.swept_too = true;
    LearnStats st;
    for (int turns = 0; !cursor.done && turns < 200; ++turns) d.refine(m, cursor, st);
    EXPECT_TRUE(cursor.done);
    EXPECT_EQ(m.table(codec::Table::HoldingRegisters).ranges,
              ranges({{0, 9}, {5000, 5000}, {6998, 7002}}));
    EXPECT_EQ(m.table(codec::Table::InputRegisters).ranges, ranges({{4099, 4100}}));
    EXPECT_TRUE(m.table(codec::Table::Coils).ranges.empty());
    EXPECT_EQ(m.table(codec::Table::HoldingRegisters).max_quantity, 10);
}

// The campaign refines between rounds: the range shows up in the summary's model, in
// model.json beside the findings, and refinement's reads are counted apart from learning's.
TEST(MapRefine, TheCampaignRefinesTheMapItLearnedAndSaysWhatItFound) {
    ThreadSlave slave(serve);
    const std::string dir = mbstorm::test::temp_dir("map-refine");
    const auto run = mbstorm::test::run_mbstorm("fuzz --target " + slave.endpoint() +
                                                    " --seed 1 --seconds 6 -q --out " + dir +
                                                    "/findings --json " + dir + "/summary.json",
                                                30);
    std::ifstream in(dir + "/summary.json");
    ASSERT_TRUE(in) << run.output;
    const nlohmann::json j = nlohmann::json::parse(in);
    EXPECT_GT(j.at("refine_requests").get<std::uint64_t>(), 0u);
    EXPECT_GT(j.at("learn_requests").get<std::uint64_t>(), 0u);
    const auto& holding = j.at("model").at("tables").at("holding-registers");
    EXPECT_EQ(holding.at("found_during_run"), nlohmann::json::parse("[[6998, 7002]]"))
        << j.at("model").dump() << " refine_requests " << j.at("refine_requests");
    EXPECT_EQ(holding.at("ranges"), nlohmann::json::parse("[[0, 9], [5000, 5000], [6998, 7002]]"));
    std::ifstream saved(dir + "/findings/model.json");
    ASSERT_TRUE(saved);
    EXPECT_EQ(nlohmann::json::parse(saved).at("tables").at("holding-registers").at("ranges"),
              holding.at("ranges"));
    std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace mbstorm::netfuzz
