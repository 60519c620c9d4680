// The coverage map as a target sees it: a System V segment attached by its id (as AFL++'s
// runtime and coverage/mbstorm_coverage.c do), hit counts in AFL's buckets, and the
// comparison log past the map.
#include <gtest/gtest.h>
#include <sys/shm.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "netfuzz/corpus.hpp"
#include "netfuzz/coverage_map.hpp"
#include "netfuzz/generator.hpp"
#include "netfuzz/wire.hpp"

using namespace mbstorm::netfuzz;
using mbstorm::Error;
using mbstorm::ErrorCode;
using mbstorm::Result;

namespace {

// The target's side: the segment attached again by id, as the runtime does.
struct TargetSide {
    std::uint8_t* map = nullptr;
    explicit TargetSide(const CoverageMap& m) {
        void* at = ::shmat(m.id(), nullptr, 0);
        if (at != reinterpret_cast<void*>(-1)) map = static_cast<std::uint8_t*>(at);
    }
    ~TargetSide() {
        if (map) ::shmdt(map);
    }
};

// The runtime's comparison log entry and header (coverage/mbstorm_coverage.c).
struct Entry {
    std::uint32_t size, reserved;
    std::uint64_t a, b;
};
constexpr std::size_t kEntriesAt = 8 + 4096 / 8;

void log_comparison(std::uint8_t* log, std::uint32_t size, std::uint64_t a, std::uint64_t b) {
    std::uint32_t magic = 0x504D434DU, count = 0;
    std::memcpy(&count, log + 4, 4);
    const Entry e{size, 0, a, b};
    std::memcpy(log + kEntriesAt + count * sizeof(Entry), &e, sizeof e);
    ++count;
    std::memcpy(log, &magic, 4);
    std::memcpy(log + 4, &count, 4);
}

std::uint16_t codec_load(const std::vector<std::uint8_t>& f, std::size_t at) {
    return static_cast<std::uint16_t>(f[at] << 8 | f[at + 1]);
}

}  // namespace

TEST(CoverageMap, HitCountsGoInAflsBuckets) {
    EXPECT_EQ(hit_bucket(0), 0);
    EXPECT_EQ(hit_bucket(1), 1);
    EXPECT_EQ(hit_bucket(2), 2);
    EXPECT_EQ(hit_bucket(3), 4);
    EXPECT_EQ(hit_bucket(4), 8);
    EXPECT_EQ(hit_bucket(7), 8);
    EXPECT_EQ(hit_bucket(8), 16);
    EXPECT_EQ(hit_bucket(16), 32);
    EXPECT_EQ(hit_bucket(32), 64);
    EXPECT_EQ(hit_bucket(127), 64);
    EXPECT_EQ(hit_bucket(128), 128);
    EXPECT_EQ(hit_bucket(255), 128);
}

TEST(CoverageMap, ACaseIsNewWhenItSetsABucketBitNoneSetBefore) {
    CoverageMap m;
    ASSERT_TRUE(m.create(1 << 16).ok());
    TargetSide t(m);
    ASSERT_NE(t.map, nullptr);
    t.map[10] = 1;
    t.map[65535] = 1;
    CoverageSample s = m.collect();
    EXPECT_TRUE(s.new_bits);
    EXPECT_EQ(s.new_edges, 2u);
    EXPECT_EQ(s.edges, 2u);
    // The same again: nothing new.
    m.clear();
    EXPECT_EQ(t.map[10], 0);
    t.map[10] = 1;
    s = m.collect();
    EXPECT_FALSE(s.new_bits);
    // The same edge hit 5 times: a new bucket, not a new edge.
    m.clear();
    t.map[10] = 5;
    s = m.collect();
    EXPECT_TRUE(s.new_bits);
    EXPECT_EQ(s.new_edges, 0u);
    EXPECT_EQ(m.edges_seen(), 2u);
}

// Calibration: a case that set new bits runs again; a cell whose bucket changed between the
// runs counts a loop's turns (a poll loop, a request read in parts), not the input. It makes no
// case new from then on, so that a run repeats with its seed; cells that held stay new.
TEST(CoverageMap, CellsThatChangeBetweenRunsOfOneCaseMakeNoCaseNew) {
    CoverageMap m;
    ASSERT_TRUE(m.create(1 << 16).ok());
    TargetSide t(m);
    ASSERT_NE(t.map, nullptr);
    t.map[10] = 1;  // the input's edge
    t.map[20] = 5;  // the poll loop's turns
    const CoverageSample first = m.collect();
    ASSERT_TRUE(first.new_bits);
    EXPECT_EQ(first.new_cells, (std::vector<std::uint32_t>{10, 20}));
    const std::vector<std::uint8_t> trace = m.trace();
    m.clear();
    t.map[10] = 1;
    t.map[20] = 9;  // another bucket: the loop turned more often this time
    EXPECT_EQ(m.mark_unstable(trace), 1u);
    EXPECT_EQ(m.unstable_cells(), 1u);
    EXPECT_TRUE(m.still_new(first));  // cell 10 held
    // A case new only in the unstable cell is not new; in a stable cell it is.
    m.clear();
    t.map[20] = 40;
    CoverageSample s = m.collect();
    EXPECT_FALSE(s.new_bits);
    EXPECT_FALSE(m.still_new(s));
    m.clear();
    t.map[10] = 2;
    t.map[20] = 100;
    s = m.collect();
    EXPECT_TRUE(s.new_bits);
    EXPECT_EQ(s.new_cells, (std::vector<std::uint32_t>{10}));
    // A case whose only new cell proves unstable in its own calibration is not new.
    m.clear();
    t.map[30] = 3;
    s = m.collect();
    const std::vector<std::uint8_t> again = m.trace();
    m.clear();
    EXPECT_EQ(m.mark_unstable(again), 1u);  // not hit at all the second time
    EXPECT_FALSE(m.still_new(s));
}

TEST(CoverageMap, ComparisonsPastTheMapAreReadInOrder) {
    CoverageMap m;
    ASSERT_TRUE(m.create(1 << 12).ok());
    TargetSide t(m);
    ASSERT_NE(t.map, nullptr);
    std::uint8_t* log = t.map + m.map_size();
    log_comparison(log, 0x84, 0x0123, 7);     // a constant 0x0123 against the input's 7
    log_comparison(log, 0x82, 0x4D42, 0x10);  // then 0x4D42 against 0x10
    log_comparison(log, 1, 0x16, 0x03);       // a byte comparison
    log_comparison(log, 4, 0x12345678, 9);    // 32 bits: two registers
    const CoverageSample s = m.collect();
    ASSERT_EQ(s.comparisons.size(), 4u);
    EXPECT_EQ(s.comparisons[0].a, 0x0123u);
    EXPECT_EQ(s.comparisons[1].a, 0x4D42u);
    EXPECT_EQ(s.comparisons[2].size, 1);
    const auto has = [&](std::uint16_t w) {
        return std::find(s.compared_words.begin(), s.compared_words.end(), w) !=
               s.compared_words.end();
    };
    EXPECT_TRUE(has(0x0123));
    EXPECT_TRUE(has(0x4D42));
    EXPECT_TRUE(has(0x1234));
    EXPECT_TRUE(has(0x5678));
    EXPECT_NE(std::find(s.compared_bytes.begin(), s.compared_bytes.end(), 0x16),
              s.compared_bytes.end());
    // clear() empties the log for the next case; constants are reported once per run.
    m.clear();
    log_comparison(log, 0x82, 0x4D42, 0x11);
    const CoverageSample again = m.collect();
    EXPECT_EQ(again.comparisons.size(), 1u);
    EXPECT_TRUE(again.compared_words.empty());
}

TEST(CoverageMap, RefusesASizeThatIsNotAPowerOfTwo) {
    CoverageMap m;
    const Error error = m.create(1000);
    EXPECT_EQ(error.code(), ErrorCode::InvalidInput);
    EXPECT_NE(error.message().find("power of two"), std::string::npos) << error.text();
}

// Input-to-state: a corpus entry's failed comparisons turn into the cases that pass them, one
// comparison alone and runs of comparisons made in a row (a compiler may test two fields as
// one branch, so neither alone reaches anything new).
TEST(CoverageCorpus, FailedComparisonsBecomeCasesThatPassThem) {
    GeneratorOptions o;
    Generator g(o);
    // Write single register 0x0010 := 0x0007 (any request will do).
    const std::vector<std::uint8_t> pdu = {0x06, 0x00, 0x10, 0x00, 0x07};
    Case entry;
    entry.steps.push_back(Step{Op::Send, 0, 0, 0, frame_pdu(pdu, 1, 1)});
    g.add_to_corpus(entry, {Comparison{4, 0x0123, 0x0010}, Comparison{2, 0x4D42, 0x0007}});
    bool address_alone = false, both = false;
    for (int i = 0; i < 3; ++i) {
        Case c;
        g.next(c);
        EXPECT_EQ(c.cls, MutationClass::CoverageMutation);
        ASSERT_EQ(c.steps.size(), 1u);
        const auto& f = c.steps[0].bytes;
        const std::uint16_t address = codec_load(f, 8), value = codec_load(f, 10);
        address_alone = address_alone || (address == 0x0123 && value == 0x0007);
        both = both || (address == 0x0123 && value == 0x4D42);
    }
    EXPECT_TRUE(address_alone);
    EXPECT_TRUE(both);
}

// --corpus: entries written and read back as they were; a file that is not an entry (a number
// out of its field's range, bad hex) is an error naming it, not a shorter corpus.
// A target that speaks RTU (or ASCII): the comparison is solved in the frame's unit and PDU,
// and the frame made again around them (its CRC or LRC follows), as the target must read it.
TEST(CoverageCorpus, FailedComparisonsInRtuAndAsciiFramesBecomeFramesThatPassThem) {
    const std::vector<std::uint8_t> pdu = {0x06, 0x00, 0x10, 0x00, 0x07};
    for (const auto framing : {mbstorm::codec::Framing::Rtu, mbstorm::codec::Framing::Ascii}) {
        GeneratorOptions o;
        o.framing = framing;
        Generator g(o);
        Case entry;
        entry.steps.push_back(Step{Op::Send, 0, 0, 0, frame_pdu(pdu, 0, 1, framing)});
        g.add_to_corpus(entry, {Comparison{4, 0x0123, 0x0010}, Comparison{2, 0x4D42, 0x0007}});
        std::vector<std::vector<std::uint8_t>> made;
        for (int i = 0; i < 3; ++i) {
            Case c;
            g.next(c);
            ASSERT_EQ(c.steps.size(), 1u);
            EXPECT_EQ(c.function, 0x06);
            made.push_back(c.steps[0].bytes);
        }
        const auto as_sent = [&](std::vector<std::uint8_t> p) {
            return frame_pdu(p, 0, 1, framing);
        };
        EXPECT_NE(std::find(made.begin(), made.end(), as_sent({0x06, 0x01, 0x23, 0x00, 0x07})),
                  made.end());
        EXPECT_NE(std::find(made.begin(), made.end(), as_sent({0x06, 0x01, 0x23, 0x4D, 0x42})),
                  made.end());
        // Mutations of the entry stay frames of the target's framing, with a checksum that holds.
        for (int i = 0; i < 200; ++i) {
            Case c;
            g.next(c);
            if (c.cls != MutationClass::CoverageMutation) continue;
            const auto& bytes = c.steps[0].bytes;
            if (framing == mbstorm::codec::Framing::Rtu) {
                EXPECT_TRUE(rtu_crc_ok(bytes));  // its length rule may no longer fit: a fuzz case
            } else {
                WireFrame f;
                ASSERT_EQ(cut_frame(bytes, framing, true, 0, f), WireCut::Frame);
                EXPECT_EQ(f.size, bytes.size());
                EXPECT_EQ(f.discard, "");
            }
        }
    }
}

// A comparison every case makes (the target's framing, its poll loop) is solved after one that
// few corpus entries made (a request handler's check of an address), however many entries
// came since: on a slow target the first would otherwise bury the second.
TEST(CoverageCorpus, TheRarestComparisonIsSolvedFirst) {
    GeneratorOptions o;
    Generator g(o);
    const Comparison everywhere{2, 0x0007, 0x1111};  // made by every entry
    const auto write_single = [](std::uint16_t address) {
        Case c;
        const std::vector<std::uint8_t> pdu = {0x06, 0x00, static_cast<std::uint8_t>(address), 0x00,
                                               0x07};
        c.steps.push_back(Step{Op::Send, 0, 0, 0, frame_pdu(pdu, 1, 1)});
        return c;
    };
    g.add_to_corpus(write_single(0x10), {everywhere, Comparison{2, 0x0010, 0x0123}});
    for (const std::uint16_t address : {0x20, 0x30, 0x40})
        g.add_to_corpus(write_single(address), {everywhere});
    Case first;
    g.next(first);
    ASSERT_EQ(first.steps.size(), 1u);
    EXPECT_EQ(codec_load(first.steps[0].bytes, 8), 0x0123);
    EXPECT_EQ(codec_load(first.steps[0].bytes, 10), 0x0007);
}

TEST(CoverageCorpus, SavedEntriesLoadBackAndBadFilesAreNamed) {
    const std::string dir =
        (std::filesystem::temp_directory_path() / ("mbstorm-corpus-" + std::to_string(::getpid())))
            .string();
    std::filesystem::remove_all(dir);
    Case c;
    c.cls = MutationClass::CoverageMutation;
    c.function = 6;
    c.steps.push_back(Step{Op::Send, 1, 250, 0, frame_pdu({0x06, 0x00, 0x10, 0x00, 0x07}, 9, 1)});
    c.steps.push_back(Step{Op::ShutdownWrite, 1, 0, 0, {}});
    ASSERT_TRUE(save_corpus_entry(dir, 0, c).ok());
    ASSERT_TRUE(save_corpus_entry(dir, 1, c).ok());
    Result<std::vector<Case>> loaded = load_corpus(dir);
    ASSERT_TRUE(loaded.ok()) << loaded.error().text();
    std::vector<Case> back = *loaded;
    ASSERT_EQ(back.size(), 2u);
    EXPECT_EQ(back[1].cls, c.cls);
    EXPECT_EQ(back[1].function, 6);
    ASSERT_EQ(back[1].steps.size(), 2u);
    EXPECT_EQ(back[1].steps[0].bytes, c.steps[0].bytes);
    EXPECT_EQ(back[1].steps[0].conn, 1);
    EXPECT_EQ(back[1].steps[0].delay_us, 250u);
    EXPECT_EQ(back[1].steps[1].op, Op::ShutdownWrite);
    for (const char* bad :
         {R"({"class": "coverage-mutation", "steps": [{"op": "send", "conn": 300, "hex": "00"}]})",
          R"({"class": "coverage-mutation", "steps": [{"op": "send", "conn": -1, "hex": "00"}]})",
          R"({"class": "coverage-mutation", "steps": [{"op": "send", "hex": "0G"}]})",
          R"({"class": "no-such-class", "steps": [{"op": "send", "hex": "00"}]})", "[1, 2"}) {
        std::ofstream(dir + "/000002.json") << bad;
        const Error error = load_corpus(dir).error();
        EXPECT_EQ(error.code(), ErrorCode::InvalidInput) << bad;
        // The place is the entry's path: the user finds the file the text names.
        EXPECT_EQ(error.place(), dir + "/000002.json") << error.text();
    }
    std::filesystem::remove_all(dir);
    loaded = load_corpus(dir);
    ASSERT_TRUE(loaded.ok());  // no folder yet: an empty corpus
    EXPECT_TRUE(loaded->empty());
}

// Each case's rarest edge: of the cells it hit, the one the fewest collected cases hit.
TEST(CoverageMap, ACaseNamesTheRarestEdgeItHit) {
    CoverageMap m;
    ASSERT_TRUE(m.create(65536).ok());
    TargetSide target(m);
    ASSERT_NE(target.map, nullptr);
    for (int i = 0; i < 5; ++i) {  // five cases through cell 100 only
        m.clear();
        target.map[100] = 1;
        EXPECT_EQ(m.collect().rarest_edge, 100u);
    }
    m.clear();
    target.map[100] = 3;
    target.map[7000] = 1;  // a case that also reaches cell 7000, hit by nobody before
    const CoverageSample s = m.collect();
    EXPECT_EQ(s.rarest_edge, 7000u);
    EXPECT_EQ(m.cases_hitting(100), 6u);
    EXPECT_EQ(m.cases_hitting(7000), 1u);
}

// Corpus entries of rare edges get more runs (FairFuzz's rule): of two entries, the one whose
// edge one case reached is picked about three times in four (half the picks go to the
// rarest, half are uniform), the one whose edge fifty cases reached about once in four.
TEST(CoverageCorpus, EntriesOfRareEdgesAreMutatedMoreOften) {
    CoverageMap m;
    ASSERT_TRUE(m.create(65536).ok());
    TargetSide target(m);
    ASSERT_NE(target.map, nullptr);
    auto run_case = [&](std::size_t cell) {
        m.clear();
        target.map[cell] = 1;
        return m.collect();
    };
    GeneratorOptions o;
    o.seed = 3;
    Generator g(o);
    g.favour_rare_edges(&m);
    Case entry;
    entry.steps.push_back(Step{Op::Send, 0, 0, 0, frame_pdu({0x03, 0x00, 0x00, 0x00, 0x01}, 1, 1)});
    g.add_to_corpus(entry, {}, run_case(10).rarest_edge);  // common: hit 50 times below
    g.add_to_corpus(entry, {}, run_case(20).rarest_edge);  // rare: hit once
    for (int i = 0; i < 49; ++i) run_case(10);
    int rare = 0;
    for (int i = 0; i < 1000; ++i) rare += g.pick_corpus_entry() == 1;
    EXPECT_GT(rare, 650) << "the rare edge's entry was picked " << rare << " times in 1000";
    EXPECT_LT(rare, 850);
}
