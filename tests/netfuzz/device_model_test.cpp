// The device model: --map parsing, model.json round trips, learning a sparse map that does not
// start at 0 (tests/tools/sparse_device_server: holding 1000-1039 and 1060-1099, input
// 3000-3015, coils 200-263, discrete 500-531, units 1 and 255, a 100 ms pause after 01 and 03),
// and the idle sentinels that tell a crash a supervisor hides.
#include <gtest/gtest.h>

#include <memory>

#include "codec/mbap.hpp"
#include "fuzz_test_support.hpp"
#include "netfuzz/campaign.hpp"
#include "netfuzz/death_watch.hpp"
#include "netfuzz/device_model.hpp"
#include "netfuzz/executor.hpp"
#include "netfuzz/field_repair.hpp"
#include "netfuzz/generator.hpp"
#include "netfuzz/wire.hpp"

namespace {

using mbstorm::codec::Table;
using namespace mbstorm::netfuzz;
using mbstorm::Error;
using mbstorm::ErrorCode;
using mbstorm::Result;

std::vector<AddressRange> ranges(std::initializer_list<std::pair<int, int>> list) {
    std::vector<AddressRange> out;
    for (auto [a, b] : list)
        out.push_back(AddressRange{static_cast<std::uint16_t>(a), static_cast<std::uint16_t>(b)});
    return out;
}

TEST(DeviceModelMap, ParsesTablesRangesAndSingleAddresses) {
    const Result<DeviceModel> parsed =
        parse_map("holding=1000-1039,holding=1060-1099,coils=0x00C8-263,input=3000");
    ASSERT_TRUE(parsed.ok()) << parsed.error().text();
    const DeviceModel& m = *parsed;
    EXPECT_EQ(m.table(Table::HoldingRegisters).ranges, ranges({{1000, 1039}, {1060, 1099}}));
    EXPECT_EQ(m.table(Table::Coils).ranges, ranges({{200, 263}}));
    EXPECT_EQ(m.table(Table::InputRegisters).ranges, ranges({{3000, 3000}}));
    EXPECT_TRUE(m.table(Table::DiscreteInputs).ranges.empty());
    // Reference numbers, as a vendor's manual lists them (the project's address rule).
    const Result<DeviceModel> refs = parse_map("holding=40001-40010");
    ASSERT_TRUE(refs.ok()) << refs.error().text();
    EXPECT_EQ(refs->table(Table::HoldingRegisters).ranges, ranges({{0, 9}}));
    EXPECT_EQ(m.table(Table::HoldingRegisters).entries(), 80u);
    EXPECT_TRUE(m.table(Table::HoldingRegisters).contains(1039));
    EXPECT_FALSE(m.table(Table::HoldingRegisters).contains(1040));
}

TEST(DeviceModelMap, AdjacentRangesMergeAndBadEntriesAreRefused) {
    const Result<DeviceModel> m = parse_map("holding=10-19,holding=20-29,holding=5-12");
    ASSERT_TRUE(m.ok()) << m.error().text();
    EXPECT_EQ(m->table(Table::HoldingRegisters).ranges, ranges({{5, 29}}));
    for (const char* bad :
         {"", "registers=1-2", "holding=5-1", "holding=1-70000", "holding", "coils=x"}) {
        const Error error = parse_map(bad).error();
        EXPECT_EQ(error.code(), ErrorCode::InvalidInput) << bad;
        EXPECT_NE(error.message().find("--map"), std::string::npos) << error.text();
    }
}

TEST(DeviceModelJson, RoundTripsEverythingItSays) {
    DeviceModel m;
    m.source = "learned";
    m.table(Table::HoldingRegisters).ranges = ranges({{1000, 1039}, {1060, 1099}});
    m.table(Table::HoldingRegisters).max_quantity = 40;
    m.table(Table::HoldingRegisters).writes = WritesStick::Yes;
    m.table(Table::Coils).ranges = ranges({{200, 263}});
    m.table(Table::Coils).writes = WritesStick::Refused;
    m.units = {1, 255};
    m.exception_pause_ms[3] = 100;
    m.partial = true;
    m.table(Table::HoldingRegisters).found_during_run = ranges({{1060, 1099}});
    const Result<DeviceModel> read = model_from_json(model_to_json(m));
    ASSERT_TRUE(read.ok()) << read.error().text();
    const DeviceModel& back = *read;
    EXPECT_EQ(back.table(Table::HoldingRegisters).ranges, m.table(Table::HoldingRegisters).ranges);
    EXPECT_EQ(back.table(Table::HoldingRegisters).max_quantity, 40);
    EXPECT_EQ(back.table(Table::HoldingRegisters).writes, WritesStick::Yes);
    EXPECT_EQ(back.table(Table::Coils).writes, WritesStick::Refused);
    EXPECT_EQ(back.units, m.units);
    EXPECT_EQ(back.exception_pause_ms, m.exception_pause_ms);
    EXPECT_TRUE(back.pauses_after_exceptions());
    EXPECT_TRUE(back.partial);
    EXPECT_EQ(back.table(Table::HoldingRegisters).found_during_run, ranges({{1060, 1099}}));
    EXPECT_FALSE(model_from_json("{\"tables\": {\"holding\": {\"ranges\": [[5, 1]]}}}").ok());
    EXPECT_FALSE(model_from_json("[]").ok());
}

// A model.json is a file the user may edit or bring from elsewhere: numbers that do not fit
// their field (found by fuzz/fuzz_inputs.cpp: 3e28 as an address was undefined behaviour)
// are refused with the field named, never converted.
TEST(DeviceModelJson, RefusesNumbersThatDoNotFitTheirField) {
    for (const char* bad : {
             R"({"tables": {"holding": {"ranges": [[3e28, 4e28]]}}})",
             R"({"tables": {"holding": {"ranges": [[-1, 5]]}}})",
             R"({"tables": {"holding": {"ranges": [[0, 65536]]}}})",
             R"({"tables": {"holding": {"ranges": [[0.5, 5]]}}})",
             R"({"tables": {"holding": {"ranges": [], "max_quantity": 1e9}}})",
             R"({"tables": {}, "units": [256]})",
             R"({"tables": {}, "units": [1.5]})",
             R"({"tables": {}, "exception_pause_ms": {"01": -3}})",
         }) {
        const Error error = model_from_json(bad).error();
        EXPECT_NE(error.message().find("whole number"), std::string::npos)
            << bad << ": " << error.text();
    }
}

struct SparseDevice {
    std::unique_ptr<mbstorm::test::Target> process;
    std::unique_ptr<TcpConnector> connector;
    TargetProfile profile;

    bool start() {
        process = std::make_unique<mbstorm::test::Target>(std::vector<std::string>{
            mbstorm::test::tool_path("sparse_device_server"), "--port", "0", "--respawn",
            "--restart-delay-ms", "20", "--exit-after-s", "120"});
        const std::string line = process->wait_for_line("PORT ");
        if (line.empty()) return false;
        const auto ep = mbstorm::net::parse_endpoint("127.0.0.1:" + line.substr(5));
        if (!ep.ok()) return false;
        connector = std::make_unique<TcpConnector>(*ep);
        return discover_target(*connector, 1, 1000, profile).ok();
    }
};

TEST(LearnDeviceModel, FindsASparseMapThatDoesNotStartAtZero) {
    SparseDevice d;
    ASSERT_TRUE(d.start());
    LearnStats stats;
    const DeviceModel m = learn_device_model(*d.connector, d.profile, LearnOptions{}, &stats);
    EXPECT_FALSE(m.partial);
    EXPECT_EQ(m.table(Table::HoldingRegisters).ranges, ranges({{1000, 1039}, {1060, 1099}}));
    EXPECT_EQ(m.table(Table::InputRegisters).ranges, ranges({{3000, 3015}}));
    EXPECT_EQ(m.table(Table::Coils).ranges, ranges({{200, 263}}));
    EXPECT_EQ(m.table(Table::DiscreteInputs).ranges, ranges({{500, 531}}));
    EXPECT_EQ(m.table(Table::HoldingRegisters).max_quantity, 40);
    EXPECT_EQ(m.table(Table::Coils).max_quantity, 64);
    EXPECT_EQ(m.table(Table::HoldingRegisters).writes, WritesStick::Yes);
    EXPECT_EQ(m.table(Table::Coils).writes, WritesStick::Yes);
    EXPECT_EQ(m.units, (std::vector<std::uint8_t>{1, 255}));
    // 100 ms after 01 and 03, nothing after 02.
    EXPECT_GE(m.exception_pause_ms[3], 60u);
    EXPECT_EQ(m.exception_pause_ms[2], 0u);
    EXPECT_TRUE(m.pauses_after_exceptions());
    EXPECT_GT(stats.requests, 4000u);
}

TEST(DeathWatch, AllSentinelsDroppingIsADeathEvenWhenTheTargetIsBackAtOnce) {
    SparseDevice d;
    ASSERT_TRUE(d.start());
    DeathWatch watch(*d.connector, 3, 1000, &d.profile);
    ASSERT_TRUE(watch.arm());
    EXPECT_FALSE(watch.died(50)) << "nothing happened yet";
    // Bug 1 of the sparse device: FC10 inside the map with a byte count that disagrees.
    Case crash;
    crash.steps.push_back(
        Step{Op::Send, 0, 0, 0, frame_pdu({0x10, 0x03, 0xE8, 0x00, 0x02, 0x02, 0, 1}, 1, 1)});
    ExecOptions eo;
    eo.watch = &watch;
    const Execution ex = execute_case(crash, *d.connector, d.profile, eo);
    EXPECT_TRUE(ex.target_down);
    EXPECT_EQ(ex.verdict.oracle, Oracle::Crash) << ex.verdict.summary;
    EXPECT_EQ(ex.verdict.rule, "target-down/fc10");
    EXPECT_FALSE(watch.armed());
    // The supervisor had it back within milliseconds: a fresh probe alone would have seen
    // nothing.
    ProbeResult back = ProbeResult::ConnectFailed;
    for (int i = 0; i < 100 && back != ProbeResult::Ok; ++i) {
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
        back = probe_target(*d.connector, d.profile, 1000);
    }
    EXPECT_EQ(back, ProbeResult::Ok);
    ASSERT_TRUE(watch.arm());
    // A harmless case: no death.
    Case read;
    read.steps.push_back(Step{Op::Send, 0, 0, 0, frame_pdu({0x03, 0x03, 0xE8, 0x00, 0x02}, 2, 1)});
    const Execution fine = execute_case(read, *d.connector, d.profile, eo);
    EXPECT_FALSE(fine.verdict) << fine.verdict.summary;
    EXPECT_TRUE(watch.armed());
}

TEST(GeneratorAimed, CasesLandInsideTheMapAndOnEveryEdge) {
    const Result<DeviceModel> parsed =
        parse_map("holding=1000-1039,holding=1060-1099,coils=200-263");
    ASSERT_TRUE(parsed.ok());
    const DeviceModel& m = *parsed;
    GeneratorOptions o;
    o.seed = 3;
    Generator g(o);
    g.use_model(&m, StateRange{0, 0x10000});
    std::size_t in_map = 0, inside = 0;
    std::set<std::uint16_t> edge_addresses;
    Case c;
    for (int i = 0; i < 20000; ++i) {
        g.next(c);
        if (c.cls != MutationClass::InMap && c.cls != MutationClass::MapEdge) continue;
        const std::vector<std::uint8_t>& f = c.steps.at(0).bytes;
        ASSERT_GE(f.size(), 10u);
        const std::uint8_t fc = f[7];
        const std::uint16_t a = mbstorm::codec::load_be16(f.data() + 8);
        const auto table = mbstorm::codec::function_table(fc);
        ASSERT_TRUE(table) << hex(f);
        if (c.cls == MutationClass::MapEdge) {
            if (fc == 0x03) edge_addresses.insert(a);
            continue;
        }
        ++in_map;
        inside += m.table(*table).contains(a);
    }
    // The in-map share (4 in 10 cases) and, but for the one-before/one-past mutation, inside.
    EXPECT_GT(in_map, 5000u);
    EXPECT_GT(inside * 10, in_map * 8) << inside << " of " << in_map;
    // FC03 at each edge of both holding ranges: first, last, one before, one past, and the
    // last full read's start (and one further).
    for (std::uint16_t a : {999, 1000, 1039, 1040, 1059, 1060, 1099, 1100})
        EXPECT_TRUE(edge_addresses.count(a)) << a;
}

TEST(ShadowMaskWrite, AWrongMaskWriteResultIsAMismatchNamedAfterTheMaskWrite) {
    TargetProfile p;
    auto info = [&](std::vector<std::uint8_t> pdu, std::uint16_t tid) {
        RequestInfo r;
        static std::vector<std::vector<std::uint8_t>> keep;
        keep.push_back(frame_pdu(pdu, tid, 1));
        describe_request(keep.back(), p, r);
        return r;
    };
    // 06: 1000 := 00F0; 16: AND 0F0F, OR F000; read back. Owed: (00F0 & 0F0F) | (F000 & F0F0)
    // = 0000 | F000 = F000. The planted bug stores (00F0 & 0F0F) | F000 = F000 too, so use
    // OR 0F00: owed (00F0 & 0F0F) | (0F00 & F0F0) = 0000; the bug stores 0F00.
    const RequestInfo w = info({0x06, 0x03, 0xE8, 0x00, 0xF0}, 1);
    const RequestInfo mask = info({0x16, 0x03, 0xE8, 0x0F, 0x0F, 0x0F, 0x00}, 2);
    const RequestInfo read = info({0x03, 0x03, 0xE8, 0x00, 0x01}, 3);
    const std::vector<std::uint8_t> w_ok = {0x06, 0x03, 0xE8, 0x00, 0xF0};
    const std::vector<std::uint8_t> mask_ok = {0x16, 0x03, 0xE8, 0x0F, 0x0F, 0x0F, 0x00};
    for (const std::uint16_t stored : {0x0000, 0x0F00}) {
        const std::vector<std::uint8_t> got = {0x03, 0x02, static_cast<std::uint8_t>(stored >> 8),
                                               static_cast<std::uint8_t>(stored)};
        std::vector<Shadow::Event> events = {
            {&w, 10, 20, w_ok, 0}, {&mask, 30, 40, mask_ok, 0}, {&read, 50, 60, got, 0}};
        const Verdict v = Shadow::check(events, StateRange{0, 0x10000});
        if (stored == 0x0000) {
            EXPECT_FALSE(v) << v.summary;
        } else {
            EXPECT_EQ(v.oracle, Oracle::SpecDeviation);
            EXPECT_EQ(v.rule, "read-after-write-mismatch(holding-registers)/fc16") << v.summary;
        }
    }
}

// Two writes of one register in the same send, acknowledged in the same reply: the second
// one's value stands (a burst-split case once read back the second and was called a mismatch
// against the first).
TEST(ShadowMaskWrite, OfTwoWritesInOneSendTheLaterInTheStreamStands) {
    TargetProfile p;
    std::vector<std::vector<std::uint8_t>> frames = {
        frame_pdu({0x06, 0x03, 0xE8, 0xA5, 0xA4}, 1, 1),
        frame_pdu({0x06, 0x03, 0xE8, 0xFF, 0xFF}, 2, 1),
        frame_pdu({0x03, 0x03, 0xE8, 0x00, 0x01}, 3, 1)};
    RequestInfo first, second, read;
    describe_request(frames[0], p, first);
    describe_request(frames[1], p, second);
    describe_request(frames[2], p, read);
    const std::vector<std::uint8_t> ack1 = {0x06, 0x03, 0xE8, 0xA5, 0xA4};
    const std::vector<std::uint8_t> ack2 = {0x06, 0x03, 0xE8, 0xFF, 0xFF};
    const std::vector<std::uint8_t> got = {0x03, 0x02, 0xFF, 0xFF};
    std::vector<Shadow::Event> events = {
        {&first, 10, 20, ack1, 0}, {&second, 10, 20, ack2, 0}, {&read, 30, 40, got, 0}};
    const Verdict v = Shadow::check(events, StateRange{0, 0x10000});
    EXPECT_FALSE(v) << v.summary;
}

TEST(ShadowMaskWrite, AValueOnlyAnotherConnectionReadsWrongIsItsOwnFault) {
    TargetProfile p;
    std::vector<std::vector<std::uint8_t>> frames = {
        frame_pdu({0x06, 0x04, 0x24, 0x12, 0x34}, 1, 1),
        frame_pdu({0x03, 0x04, 0x24, 0x00, 0x01}, 2, 1),
        frame_pdu({0x03, 0x04, 0x24, 0x00, 0x01}, 3, 1)};
    RequestInfo w, same, other;
    describe_request(frames[0], p, w);
    describe_request(frames[1], p, same);
    describe_request(frames[2], p, other);
    const std::vector<std::uint8_t> ack = {0x06, 0x04, 0x24, 0x12, 0x34};
    const std::vector<std::uint8_t> good = {0x03, 0x02, 0x12, 0x34};
    const std::vector<std::uint8_t> old = {0x03, 0x02, 0x04, 0x24};
    std::vector<Shadow::Event> events = {
        {&w, 10, 20, ack, 0}, {&same, 30, 40, good, 0}, {&other, 30, 40, old, 1}};
    const Verdict v = Shadow::check(events, StateRange{0, 0x10000});
    EXPECT_EQ(v.rule, "read-after-write-mismatch-other-connection(holding-registers)/fc06")
        << v.summary;
}

}  // namespace

namespace {

// Field-level minimisation: only the address fields move, into the first range of the
// function's table; requests already inside the map, or without an address, are left alone.
TEST(FieldRepair, MovesEveryAddressOutsideTheMapToItsTableAndNothingElse) {
    DeviceModel model;
    model.table(Table::Coils).ranges = ranges({{200, 263}});
    model.table(Table::HoldingRegisters).ranges = ranges({{1000, 1039}, {1060, 1099}});
    // FC 05 at 0x2000 with value 0x1234 (invalid): the value stays wrong, the address moves.
    const std::vector<std::uint8_t> coil = {0x05, 0x20, 0x00, 0x12, 0x34};
    const auto moved = with_addresses_in_map(coil, model);
    ASSERT_TRUE(moved);
    EXPECT_EQ(*moved, (std::vector<std::uint8_t>{0x05, 0x00, 0xC8, 0x12, 0x34}));
    // FC 17: both ranges' starts, each only if it is outside.
    const std::vector<std::uint8_t> rw = {0x17, 0x03, 0xE8, 0x00, 0x01, 0x50,
                                          0x00, 0x00, 0x01, 0x02, 0xAB, 0xCD};
    const auto rw_moved = with_addresses_in_map(rw, model);
    ASSERT_TRUE(rw_moved);
    EXPECT_EQ(mbstorm::codec::load_be16(rw_moved->data() + 1), 1000);
    EXPECT_EQ(mbstorm::codec::load_be16(rw_moved->data() + 5), 1000);
    EXPECT_TRUE(std::equal(rw.begin() + 7, rw.end(), rw_moved->begin() + 7));
    // Inside already, no address, a table the model knows nothing of, too short: nothing.
    EXPECT_FALSE(with_addresses_in_map(std::vector<std::uint8_t>{0x06, 0x03, 0xE8, 0, 1}, model));
    EXPECT_FALSE(with_addresses_in_map(std::vector<std::uint8_t>{0x08, 0x00, 0x00}, model));
    EXPECT_FALSE(with_addresses_in_map(std::vector<std::uint8_t>{0x04, 0x20, 0x00, 0, 1}, model));
    EXPECT_FALSE(with_addresses_in_map(std::vector<std::uint8_t>{0x05, 0x20}, model));
}

// The valid request a stub's answer is compared with: valid for the codec, inside one range
// of the map for codes with a table, any valid one for codes without.
TEST(FieldRepair, AValidRequestInTheMapOfEachCode) {
    DeviceModel model;
    model.table(Table::Coils).ranges = ranges({{200, 263}});
    model.table(Table::HoldingRegisters).ranges = ranges({{1000, 1039}, {1060, 1099}});
    for (const std::uint8_t fc : {0x01, 0x03, 0x05, 0x06, 0x0F, 0x10, 0x16, 0x17, 0x14, 0x08}) {
        const auto pdu = valid_request_in_map(fc, model);
        ASSERT_TRUE(pdu) << int(fc);
        mbstorm::codec::Request q;
        ASSERT_TRUE(mbstorm::codec::decode_request(*pdu, q).ok()) << int(fc);
        const auto table = mbstorm::codec::function_table(fc);
        if (!table) continue;
        const AddressRange* r = model.table(*table).range_of(q.address);
        ASSERT_NE(r, nullptr) << int(fc);
        EXPECT_LE(q.address + std::max<int>(q.quantity, 1) - 1, r->last) << int(fc);
    }
    // No range of the table known: no request of it is inside the map.
    EXPECT_FALSE(valid_request_in_map(0x04, model));
    EXPECT_FALSE(valid_request_in_map(0x99, model));
}

// A step's one request read as MBAP and written back in the step's framing (RTU: the CRC
// made again); a step of two frames, or of another code, is not one request.
TEST(FieldRepair, AStepsRequestIsReadAndWrittenInItsFraming) {
    using mbstorm::codec::Framing;
    const std::vector<std::uint8_t> mbap = {0x12, 0x34, 0, 0, 0, 6, 0x11, 0x03, 0, 0x6B, 0, 3};
    Step rtu{Op::Send, 0, 0, 0, reframe(mbap, Framing::Rtu)};
    const auto read = step_request(rtu, 0x03, Framing::Rtu);
    ASSERT_TRUE(read);
    EXPECT_TRUE(std::equal(read->begin() + 6, read->end(), mbap.begin() + 6));
    EXPECT_FALSE(step_request(rtu, 0x04, Framing::Rtu));
    std::vector<std::uint8_t> changed = *read;
    changed.back() = 4;
    set_step_request(rtu, changed, Framing::Rtu);
    EXPECT_EQ(rtu.bytes, reframe(changed, Framing::Rtu));
    Step two{Op::Send, 0, 0, 0, mbap};
    two.bytes.insert(two.bytes.end(), mbap.begin(), mbap.end());
    EXPECT_FALSE(step_request(two, 0x03, Framing::Mbap));
    EXPECT_TRUE(step_request(Step{Op::Send, 0, 0, 0, mbap}, 0x03, Framing::Mbap));
}

std::vector<std::string> names(const std::vector<RequestField>& fields) {
    std::vector<std::string> out;
    for (const RequestField f : fields) out.emplace_back(field_name(f));
    return out;
}
using Names = std::vector<std::string>;

// Field-level minimisation's facts (issue #26 item 4): which fields of a request are wrong, in
// the order a server checks them, and each made right alone.
TEST(FieldRepair, NamesEachWrongFieldInCheckOrder) {
    DeviceModel model;
    model.table(Table::Coils).ranges = ranges({{200, 263}});
    model.table(Table::HoldingRegisters).ranges = ranges({{1000, 1039}, {1060, 1099}});
    // FC 0F at 0x2000, quantity 0x4001 (over 1968), byte count 2, one data byte: every field.
    const std::vector<std::uint8_t> coils = {0x0F, 0x20, 0x00, 0x40, 0x01, 0x02, 0xAA};
    EXPECT_EQ(names(wrong_fields(coils, model)),
              (Names{"quantity", "byte-count", "data-length", "address"}));
    // A valid FC 10 inside the map: nothing; its byte count one too large: only that.
    const std::vector<std::uint8_t> regs = {0x10, 0x03, 0xE8, 0, 2, 4, 0, 1, 0, 2};
    EXPECT_TRUE(wrong_fields(regs, model).empty());
    std::vector<std::uint8_t> long_count = regs;
    long_count[5] = 5;
    EXPECT_EQ(names(wrong_fields(long_count, model)), (Names{"byte-count", "data-length"}));
    // FC 17: the write range runs past the first block's end (1039) while the read range fits.
    const std::vector<std::uint8_t> rw = {0x17, 0x03, 0xE8, 0, 1, 0x04, 0x0F, 0, 2, 4, 0, 1, 0, 2};
    EXPECT_EQ(names(wrong_fields(rw, model)), (Names{"write-address"}));
    // FC 05's value, and an address the model does not know the table of (no judgement).
    EXPECT_EQ(names(wrong_fields(std::vector<std::uint8_t>{0x05, 0, 0xC8, 0x12, 0x34}, model)),
              (Names{"value"}));
    EXPECT_EQ(names(wrong_fields(std::vector<std::uint8_t>{0x04, 0x20, 0, 0, 0}, model)),
              (Names{"quantity"}));
    EXPECT_TRUE(wrong_fields(std::vector<std::uint8_t>{0x99, 1, 2}, model).empty());
}

TEST(DeviceModelMap, ANeighbourOfARangeIsRefusedUnlessAnotherRangeHoldsIt) {
    TableModel t;
    t.ranges = ranges({{1000, 1039}, {1060, 1099}});
    EXPECT_EQ(refused_neighbours(t), (std::vector<std::uint16_t>{999, 1040, 1059, 1100}));
    t.ranges = ranges({{0, 9}, {0xFFF0, 0xFFFF}});
    EXPECT_EQ(refused_neighbours(t), (std::vector<std::uint16_t>{10, 0xFFEF}));
    t.ranges = ranges({{5, 5}, {7, 7}});
    EXPECT_EQ(refused_neighbours(t), (std::vector<std::uint16_t>{4, 6, 6, 8}));
    // Ranges as a model file may give them, not merged: the address between is no neighbour.
    t.ranges = {AddressRange{0, 9}, AddressRange{10, 19}};
    EXPECT_EQ(refused_neighbours(t), (std::vector<std::uint16_t>{20}));
}

TEST(DeviceModelMap, TheLivenessProbeReadsTheFirstAddressOfTheFirstTableTheTargetServes) {
    DeviceModel model;
    std::array<bool, 256> unsupported{};
    EXPECT_FALSE(probe_in_map(model, unsupported));
    model.table(Table::Coils).ranges = ranges({{200, 263}});
    EXPECT_EQ(*probe_in_map(model, unsupported), (std::vector<std::uint8_t>{0x01, 0, 0xC8, 0, 1}));
    model.table(Table::HoldingRegisters).ranges = ranges({{1000, 1099}});
    model.table(Table::InputRegisters).ranges = ranges({{5, 9}});
    EXPECT_EQ(*probe_in_map(model, unsupported),
              (std::vector<std::uint8_t>{0x03, 0x03, 0xE8, 0, 1}));
    unsupported[0x03] = true;
    EXPECT_EQ(*probe_in_map(model, unsupported), (std::vector<std::uint8_t>{0x04, 0, 5, 0, 1}));
}

TEST(FieldRepair, SaysWhichBoundAWrongCountBreaks) {
    DeviceModel model;
    model.table(Table::HoldingRegisters).ranges = ranges({{1000, 1099}});
    // FC 10 at 1000: 2 registers, byte count 4, 4 data bytes; then each count off each way.
    const std::vector<std::uint8_t> regs = {0x10, 0x03, 0xE8, 0, 2, 4, 0, 1, 0, 2};
    EXPECT_EQ(wrong_count_side(regs, RequestField::ByteCount, model), 0);
    std::vector<std::uint8_t> pdu = regs;
    pdu[5] = 6;
    EXPECT_EQ(wrong_count_side(pdu, RequestField::ByteCount, model), 1);
    EXPECT_EQ(wrong_count_side(pdu, RequestField::DataLength, model), -1);
    pdu[5] = 2;
    EXPECT_EQ(wrong_count_side(pdu, RequestField::ByteCount, model), -1);
    EXPECT_EQ(wrong_count_side(pdu, RequestField::DataLength, model), 1);
    pdu = regs;
    pdu[4] = 0;  // quantity 0
    EXPECT_EQ(wrong_count_side(pdu, RequestField::Quantity, model), -1);
    pdu[3] = 0x40;  // quantity 0x4000
    EXPECT_EQ(wrong_count_side(pdu, RequestField::Quantity, model), 1);
    EXPECT_EQ(wrong_count_side(std::vector<std::uint8_t>{0x05, 0, 0, 0x12, 0x34},
                               RequestField::Value, model),
              0);
}

TEST(FieldRepair, MakesOneFieldRightAndLeavesTheRest) {
    DeviceModel model;
    model.table(Table::Coils).ranges = ranges({{200, 263}});
    model.table(Table::HoldingRegisters).ranges = ranges({{1000, 1003}, {1060, 1099}});
    const std::vector<std::uint8_t> coils = {0x0F, 0x20, 0x00, 0x40, 0x01, 0x02, 0xAA};
    // The quantity takes what the byte count announces (2 bytes: 16 coils).
    EXPECT_EQ(*with_field_repaired(coils, RequestField::Quantity, model),
              (std::vector<std::uint8_t>{0x0F, 0x20, 0x00, 0x00, 0x10, 0x02, 0xAA}));
    // The data is padded to the byte count.
    EXPECT_EQ(*with_field_repaired(coils, RequestField::DataLength, model),
              (std::vector<std::uint8_t>{0x0F, 0x20, 0x00, 0x40, 0x01, 0x02, 0xAA, 0x00}));
    // The address moves to the first coil of the map.
    EXPECT_EQ(*with_field_repaired(coils, RequestField::Address, model),
              (std::vector<std::uint8_t>{0x0F, 0x00, 0xC8, 0x40, 0x01, 0x02, 0xAA}));
    // A byte count made right takes its data along when the data agreed with it.
    const std::vector<std::uint8_t> regs = {0x10, 0x04, 0x24, 0, 1, 4, 0, 1, 0, 2};
    EXPECT_EQ(*with_field_repaired(regs, RequestField::ByteCount, model),
              (std::vector<std::uint8_t>{0x10, 0x04, 0x24, 0, 1, 2, 0, 1}));
    EXPECT_TRUE(
        wrong_fields(*with_field_repaired(regs, RequestField::ByteCount, model), model).empty());
    // Five registers do not fit the four-register block at 1000: the block at 1060 holds them.
    const std::vector<std::uint8_t> five = {0x03, 0x20, 0x00, 0, 5};
    EXPECT_EQ(mbstorm::codec::load_be16(
                  with_field_repaired(five, RequestField::Address, model)->data() + 1),
              1060);
    EXPECT_EQ(*with_field_repaired(std::vector<std::uint8_t>{0x05, 0, 0xC8, 0x12, 0x34},
                                   RequestField::Value, model),
              (std::vector<std::uint8_t>{0x05, 0, 0xC8, 0xFF, 0x00}));
    // A field that is right already, or that cannot be made right: nothing.
    EXPECT_FALSE(with_field_repaired(regs, RequestField::Address, model));
    EXPECT_FALSE(with_field_repaired(std::vector<std::uint8_t>{0x02, 0x20, 0, 0, 1},
                                     RequestField::Address, model));
}

}  // namespace
