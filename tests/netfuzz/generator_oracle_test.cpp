// Unit tests of the generator, the oracles, minimisation and the finding format.
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <set>

#include "codec/pdu.hpp"
#include "netfuzz/cross_transport.hpp"
#include "netfuzz/finding.hpp"
#include "netfuzz/generator.hpp"
#include "netfuzz/minimize.hpp"
#include "netfuzz/oracle.hpp"
#include "netfuzz/wire.hpp"

namespace mbstorm::netfuzz {
namespace {

std::vector<std::uint8_t> adu(std::uint16_t tid, const std::vector<std::uint8_t>& pdu,
                              std::uint8_t unit = 1, std::uint16_t pid = 0) {
    std::vector<std::uint8_t> f(7 + pdu.size());
    codec::store_be16(f.data(), tid);
    codec::store_be16(f.data() + 2, pid);
    codec::store_be16(f.data() + 4, static_cast<std::uint16_t>(pdu.size() + 1));
    f[6] = unit;
    for (std::size_t i = 0; i < pdu.size(); ++i) f[7 + i] = pdu[i];
    return f;
}

TargetProfile profile() {
    TargetProfile p;
    p.probe_pdu = {0x03, 0, 0, 0, 1};
    return p;
}

GeneratorOptions options(std::uint64_t seed, unsigned isolated_per_mille) {
    GeneratorOptions o;
    o.seed = seed;
    o.isolated_per_mille = isolated_per_mille;
    return o;
}

TEST(Generator, SameSeedSameBytes) {
    Generator a(options(42, 100)), b(options(42, 100));
    Case x, y;
    for (int i = 0; i < 5000; ++i) {
        a.next(x);
        b.next(y);
        ASSERT_EQ(x.steps.size(), y.steps.size());
        for (std::size_t k = 0; k < x.steps.size(); ++k)
            ASSERT_EQ(x.steps[k].bytes, y.steps[k].bytes);
    }
}

TEST(Generator, StructuredSeedsCoverEveryFunctionCodeAndLimit) {
    const auto seeds = structured_pdus();
    std::set<std::uint8_t> fcs;
    bool fc0f_qty0 = false, fc03_qty126 = false, fc2b_code4_ext = false;
    for (const auto& s : seeds) {
        fcs.insert(s[0]);
        if (s.size() >= 5 && s[0] == 0x0F && s[3] == 0 && s[4] == 0) fc0f_qty0 = true;
        if (s.size() == 5 && s[0] == 0x03 && s[3] == 0 && s[4] == 126) fc03_qty126 = true;
        if (s.size() == 4 && s[0] == 0x2B && s[2] == 4 && s[3] >= 0x80) fc2b_code4_ext = true;
    }
    EXPECT_EQ(fcs.size(), 256u);
    EXPECT_TRUE(fc0f_qty0);
    EXPECT_TRUE(fc03_qty126);
    EXPECT_TRUE(fc2b_code4_ext);
}

TEST(Generator, EveryClassAppearsAndWritesStayOutOfTheStatefulRange) {
    Generator g(options(1, 200));
    std::set<MutationClass> classes;
    Case c;
    for (int i = 0; i < 40000; ++i) {
        g.next(c);
        classes.insert(c.cls);
        if (c.cls == MutationClass::StatefulSame || c.cls == MutationClass::StatefulCross) continue;
        for (const Step& s : c.steps) {
            if (s.bytes.size() < 12 || c.cls == MutationClass::Coalesced) continue;
            const std::uint8_t fc = s.bytes[7];
            if (fc != 0x06 && fc != 0x05) continue;
            const std::uint16_t a = codec::load_be16(s.bytes.data() + 8);
            EXPECT_FALSE(a >= kStateBase && a < kStateBase + kStateSpan) << hex(s.bytes);
        }
    }
    // All but naive, those that speak the other transport (the campaign runs them itself),
    // the four of RTU/ASCII framing (generator_framing.cpp), the two aimed at a device
    // model (none given here: GeneratorAimed below) and the coverage corpus's (no corpus
    // without --coverage: CoverageCorpus in coverage_map_test.cpp).
    std::size_t generated = 0;
    for (std::size_t i = 0; i < static_cast<std::size_t>(MutationClass::Count); ++i) {
        const auto k = static_cast<MutationClass>(i);
        const bool framing_only = k == MutationClass::BadChecksum ||
                                  k == MutationClass::BrokenSilence ||
                                  k == MutationClass::NoSilence || k == MutationClass::Noise;
        if (framing_only) {
            EXPECT_EQ(classes.count(k), 0u) << class_name(k);
        }
        const bool model_only = k == MutationClass::InMap || k == MutationClass::MapEdge;
        EXPECT_TRUE(!model_only || classes.count(k) == 0) << class_name(k);
        // Corpus mutations, and the campaign's question to a target whose silences do not
        // repeat (campaign.cpp: check_random_drops).
        const bool corpus_only =
            k == MutationClass::CoverageMutation || k == MutationClass::Repeated;
        EXPECT_TRUE(!corpus_only || classes.count(k) == 0) << class_name(k);
        generated += k != MutationClass::NaiveRandom && !is_cross_transport(k) && !framing_only &&
                     !model_only && !corpus_only;
    }
    EXPECT_EQ(classes.size(), generated);
}

// Diagnostics 0001 (restart) and 0004 (listen-only) may rightly silence a device: no case
// sends them, however it was made (structured, recorded mutation or random bytes). A recorded
// mutation once did, and pymodbus's silence after 08 00 04 was reported as a hang.
TEST(Generator, NeverSendsRestartOrListenOnly) {
    for (bool naive : {false, true}) {
        GeneratorOptions o = options(3, 100);
        o.naive = naive;
        Generator g(o);
        Case c;
        int isolated = 0;
        for (int i = 0; i < 60000; ++i) {
            g.next(c);
            isolated += !c.pipelinable;
            // What each connection's server reads, pieces joined, framed by MBAP length as a
            // server frames it (a lying length frames what follows as it says).
            std::map<std::uint8_t, std::vector<std::uint8_t>> streams;
            for (const Step& s : c.steps)
                if (s.op == Op::Send)
                    streams[s.conn].insert(streams[s.conn].end(), s.bytes.begin(), s.bytes.end());
            for (const auto& [conn, bytes] : streams) {
                for (std::size_t off = 0; off + 10 <= bytes.size();) {
                    const std::size_t length = codec::load_be16(bytes.data() + off + 4);
                    const std::uint8_t* pdu = bytes.data() + off + 7;
                    if (pdu[0] == 0x08 && pdu[1] == 0x00) {
                        ASSERT_NE(pdu[2], 0x01) << hex(bytes);
                        ASSERT_NE(pdu[2], 0x04) << hex(bytes);
                    }
                    if (length < 2) break;
                    off += 6 + length;
                }
            }
        }
        if (!naive) {
            EXPECT_GT(isolated, 1000) << "the isolated cases were looked at too";
        }
    }
}

// Stateful register cases read back with every register reader: FC 03 on both connections,
// then FC 17's read part over the same window (its own write lands outside the window).
TEST(Generator, StatefulRegisterCasesReadBackWithFc17Too) {
    Generator g(options(5, 1000));
    Case c;
    int register_cases = 0, with_fc17_reader = 0;
    for (int i = 0; i < 20000; ++i) {
        g.next(c);
        if (c.cls != MutationClass::StatefulSame && c.cls != MutationClass::StatefulCross) continue;
        if (c.function == 0x05 || c.function == 0x0F) continue;
        ++register_cases;
        const Step& last = c.steps.back();
        ASSERT_GE(last.bytes.size(), 7u + 10u);
        if (last.bytes[7] != 0x17) continue;
        ++with_fc17_reader;
        const std::uint16_t read = codec::load_be16(last.bytes.data() + 8);
        const std::uint16_t read_qty = codec::load_be16(last.bytes.data() + 10);
        const std::uint16_t write = codec::load_be16(last.bytes.data() + 12);
        EXPECT_TRUE(write < read || write >= read + read_qty) << hex(last.bytes);
        EXPECT_TRUE(StateRange{}.contains(write)) << hex(last.bytes);
    }
    ASSERT_GT(register_cases, 50);
    EXPECT_EQ(with_fc17_reader, register_cases);
}

// A request whose PDU is shorter or longer than its function code implies, whatever the
// codec's first complaint about it (here a read quantity of 126 comes first).
TEST(Oracle, PduLengthMismatchIsJudgedByTheFunctionCodesLengthRule) {
    auto mismatch = [](const std::vector<std::uint8_t>& pdu) {
        const auto f = adu(1, pdu);
        RequestInfo info;
        describe_request(codec::Bytes(f.data(), f.size()), profile(), info);
        return pdu_length_mismatch(info);
    };
    EXPECT_FALSE(mismatch({0x03, 0, 0, 0, 1}));
    EXPECT_FALSE(mismatch({0x03, 0, 0, 0, 126}));     // invalid, but the right length
    EXPECT_TRUE(mismatch({0x01, 0xFE, 0x00, 0x02}));  // truncated
    EXPECT_TRUE(mismatch({0x03, 0, 0, 0, 1, 0}));     // trailing byte
    EXPECT_TRUE(mismatch({0x10, 0, 0, 0}));           // cut before its byte count
    EXPECT_TRUE(
        mismatch({0x17, 0x01, 0, 0, 0x7E, 0x01, 0x7D, 0, 0x7A, 0xF5}));  // count 245, no data
    EXPECT_TRUE(mismatch({0xB9}));                                       // no length rule at all
    EXPECT_FALSE(mismatch({0x10, 0, 0, 0, 1, 2, 0, 0}));
}

TEST(Oracle, WrongExceptionCodeIsASpecDeviation) {
    // FC03 quantity 0 at 0xFFFF: 03 is owed (quantity before address, v1.1b3).
    const auto req = adu(1, {0x03, 0xFF, 0xFF, 0x00, 0x00});
    RequestInfo rq;
    describe_request(req, profile(), rq);
    EXPECT_EQ(rq.status.exception, codec::ExceptionCode::IllegalDataValue);
    EXPECT_EQ(judge_response(rq, adu(1, {0x83, 0x02}), profile()).oracle, Oracle::SpecDeviation);
    EXPECT_FALSE(judge_response(rq, adu(1, {0x83, 0x03}), profile()));
    EXPECT_FALSE(judge_response(rq, adu(1, {0x83, 0x06}), profile()));  // busy is always allowed
}

TEST(Oracle, NormalAnswerChecks) {
    const auto req = adu(7, {0x03, 0x00, 0x10, 0x00, 0x02});
    RequestInfo rq;
    describe_request(req, profile(), rq);
    EXPECT_FALSE(judge_response(rq, adu(7, {0x03, 0x04, 1, 2, 3, 4}), profile()));
    EXPECT_EQ(judge_response(rq, adu(7, {0x03, 0x02, 1, 2}), profile()).oracle,
              Oracle::MalformedResponse);
    EXPECT_EQ(judge_response(rq, adu(7, {0x04, 0x04, 1, 2, 3, 4}), profile()).oracle,
              Oracle::MalformedResponse);
    EXPECT_EQ(judge_response(rq, adu(7, {0x03, 0x04, 1, 2, 3, 4}, 9), profile()).oracle,
              Oracle::MalformedResponse);
    EXPECT_FALSE(judge_response(rq, adu(7, {0x83, 0x02}), profile()));  // a smaller table is fine
    EXPECT_EQ(judge_response(rq, adu(7, {0x83, 0x03}), profile()).oracle, Oracle::SpecDeviation);
}

// v1.1b3's request flows check quantities and byte counts, never the PDU's length beyond them
// (FC 07, 0B, 0C, 11 have no 03 branch at all): bytes past what the function code needs may be
// ignored. pymodbus answering FC 0C with one trailing byte was a false positive (issue #26).
TEST(Oracle, TrailingBytesMayBeIgnoredButTheRestOfTheRequestIsStillJudged) {
    RequestInfo rq;
    const auto comm_event_log = adu(4, {0x0C, 0x55});
    describe_request(comm_event_log, profile(), rq);
    ASSERT_EQ(rq.status.error, codec::CodecError::TrailingBytes);
    EXPECT_FALSE(judge_response(rq, adu(4, {0x0C, 0x06, 0, 0, 0, 0, 0, 0}), profile()));
    EXPECT_FALSE(judge_response(rq, adu(4, {0x8C, 0x03}), profile()));  // the codec's own reading
    // FC 10 with one byte past its values, quantity out of range: 03 is owed all the same.
    const auto too_many = adu(5, {0x10, 0x00, 0x00, 0x00, 0x00, 0x00, 0x77});
    describe_request(too_many, profile(), rq);
    EXPECT_EQ(judge_response(rq, adu(5, {0x10, 0x00, 0x00, 0x00, 0x00}), profile()).rule,
              "invalid-request-answered-normally(owes-03)/fc10");
    // A read with a trailing byte answered with the wrong data size is still malformed.
    const auto read = adu(6, {0x03, 0x00, 0x10, 0x00, 0x02, 0x00});
    describe_request(read, profile(), rq);
    EXPECT_EQ(judge_response(rq, adu(6, {0x03, 0x02, 1, 2}), profile()).oracle,
              Oracle::MalformedResponse);
    EXPECT_FALSE(judge_response(rq, adu(6, {0x03, 0x04, 1, 2, 3, 4}), profile()));
}

// One finding per missing check: the check that owes the exception, in the handler of the
// function code. pymodbus ignoring FC 0F's quantity answered both a quantity out of range and a
// byte count that disagrees (one check in v1.1b3's flow): one rule. FC 14 is another handler.
TEST(Oracle, AnInvalidRequestAnsweredNormallyIsNamedAfterTheOwedCheckAndTheFunction) {
    // (RequestInfo holds views of the frames: they stay alive.)
    const auto quantity_frame = adu(1, {0x0F, 0x00, 0x00, 0x40, 0x01, 0x01, 0xFF});
    const auto byte_count_frame = adu(2, {0x0F, 0x00, 0x00, 0x00, 0x08, 0x02, 0xFF, 0x00});
    const auto file_frame = adu(3, {0x14, 0x03, 0x06, 0x00, 0x01});
    RequestInfo quantity, byte_count, file;
    describe_request(quantity_frame, profile(), quantity);
    describe_request(byte_count_frame, profile(), byte_count);
    describe_request(file_frame, profile(), file);
    ASSERT_EQ(quantity.status.error, codec::CodecError::QuantityOutOfRange);
    ASSERT_EQ(byte_count.status.error, codec::CodecError::ByteCountMismatch);
    const Verdict a = judge_response(quantity, adu(1, {0x0F, 0x00, 0x00, 0x40, 0x01}), profile());
    const Verdict b = judge_response(byte_count, adu(2, {0x0F, 0x00, 0x00, 0x00, 0x08}), profile());
    const Verdict c = judge_response(file, adu(3, {0x14, 0x00}), profile());
    EXPECT_EQ(a.rule, "invalid-request-answered-normally(owes-03)/fc0F");
    EXPECT_EQ(root_cause_key(a), root_cause_key(b));
    EXPECT_EQ(c.rule, "invalid-request-answered-normally(owes-03)/fc14");
}

// A frame acted on before it was whole shows as an answer to a started frame, or a close or
// silence on a split request: one root cause (pymodbus's framer: two findings before).
Verdict verdict(Oracle oracle, std::string rule) {
    Verdict v;
    v.oracle = oracle;
    v.rule = std::move(rule);
    return v;
}

TEST(RootCause, AFrameActedOnBeforeItWasWholeIsOneRootCauseHoweverItShows) {
    const Verdict answered = verdict(Oracle::MalformedResponse, kAnswersPartialFrameRule);
    const Verdict closed =
        verdict(Oracle::UnexpectedClose, "close-with-request-pending/partial-frame");
    const Verdict silent = verdict(Oracle::Hang, "no-answer/partial-frame");
    EXPECT_EQ(root_cause_key(answered), root_cause_key(closed));
    EXPECT_EQ(root_cause_key(answered), root_cause_key(silent));
    EXPECT_TRUE(same_fault(answered, closed));
    // A whole-server stall on a partial frame is another defect.
    const Verdict stall = verdict(Oracle::Hang, "stalls-other-connections(partial-frame)");
    EXPECT_NE(root_cause_key(stall), root_cause_key(closed));
    EXPECT_FALSE(same_fault(stall, closed));
}

TEST(Oracle, AnswerToNonZeroProtocolIdIsADeviation) {
    const auto req = adu(3, {0x03, 0, 0, 0, 1}, 1, 0x0001);
    RequestInfo rq;
    describe_request(req, profile(), rq);
    EXPECT_EQ(rq.expect, Expect::MustBeSilent);
    EXPECT_EQ(judge_response(rq, adu(3, {0x03, 0x02, 0, 0}), profile()).oracle,
              Oracle::SpecDeviation);
}

TEST(Oracle, ShadowFindsReadAfterWriteMismatch) {
    const auto w = adu(1, {0x06, 0x60, 0x10, 0x12, 0x34});
    const auto r = adu(2, {0x03, 0x60, 0x10, 0x00, 0x01});
    RequestInfo wi, ri;
    describe_request(w, profile(), wi);
    describe_request(r, profile(), ri);
    const std::vector<std::uint8_t> wrsp = {0x06, 0x60, 0x10, 0x12, 0x34};
    const std::vector<std::uint8_t> good = {0x03, 0x02, 0x12, 0x34}, bad = {0x03, 0x02, 0x00, 0x00};
    std::vector<Shadow::Event> ev = {{&wi, 10, 20, wrsp}, {&ri, 30, 40, good}};
    EXPECT_FALSE(Shadow::check(ev, StateRange{}));
    ev[1].response_pdu = bad;
    EXPECT_EQ(Shadow::check(ev, StateRange{}).oracle, Oracle::SpecDeviation);
    // A read sent before the write was acknowledged proves nothing.
    ev[1].sent_ns = 15;
    EXPECT_FALSE(Shadow::check(ev, StateRange{}));
}

TEST(Oracle, RelocateKeepsWritesOutOfTheStatefulRange) {
    auto f = adu(1, {0x10, 0x60, 0x00, 0x00, 0x01, 0x02, 0x00, 0x00});
    relocate_writes(f.data(), f.size(), StateRange{});
    const std::uint16_t a = codec::load_be16(f.data() + 8);
    EXPECT_TRUE(a < kStateBase || a >= kStateBase + kStateSpan);
}

TEST(Minimize, ShrinksCoalescedFramesToTheCulprit) {
    Case c;
    c.cls = MutationClass::Coalesced;
    std::vector<std::uint8_t> all;
    for (std::uint16_t t = 0; t < 10; ++t) {
        const auto f = adu(t, {static_cast<std::uint8_t>(t == 6 ? 0x0F : 0x03), 0, 0, 0, 1});
        all.insert(all.end(), f.begin(), f.end());
    }
    c.steps.push_back(Step{Op::Send, 0, 0, 0, all});
    int runs = 0;
    const Case small = minimize_case(
        c,
        [&](const Case& k) {
            ++runs;
            for (const Step& s : k.steps)
                if (s.bytes.size() > 7 && s.bytes[7] == 0x0F) return true;
            return false;
        },
        100);
    ASSERT_EQ(small.steps.size(), 1u);
    EXPECT_EQ(small.steps[0].bytes[7], 0x0F);
    EXPECT_LT(runs, 40);
}

TEST(Minimize, CutsAFramesPduToTheShortestTailThatStillFires) {
    // FC16 writing 8 registers; the "fault" needs only the function code and the address.
    Case c;
    c.steps.push_back(
        Step{Op::Send, 0, 0, 0, adu(3, {0x10, 0x12, 0x34, 0x00, 0x08, 0x10, 1,  2,  3,  4,  5,
                                        6,    7,    8,    9,    10,   11,   12, 13, 14, 15, 16})});
    int runs = 0;
    const Case small = minimize_case(
        c,
        [&](const Case& k) {
            ++runs;
            const auto& b = k.steps[0].bytes;
            // Every candidate is still one well-framed ADU.
            EXPECT_EQ(b.size(), 6u + codec::load_be16(b.data() + 4));
            return b.size() >= 10 && b[7] == 0x10 && b[8] == 0x12 && b[9] == 0x34;
        },
        40);
    ASSERT_EQ(small.steps.size(), 1u);
    EXPECT_EQ(small.steps[0].bytes, adu(3, {0x10, 0x12, 0x34}));
    EXPECT_LE(runs, 6);  // bisection over a 22-byte PDU
}

TEST(Minimize, LeavesDeliberatelyMisframedBytesAlone) {
    Case c;
    auto bytes = adu(1, {0x03, 0, 0, 0, 1});
    bytes[5] = 0x40;  // MBAP length says 64: a transport case, not a frame to cut
    c.steps.push_back(Step{Op::Send, 0, 0, 0, bytes});
    int runs = 0;
    const Case small = minimize_case(
        c,
        [&](const Case&) {
            ++runs;
            return true;
        },
        40);
    EXPECT_EQ(small.steps[0].bytes, bytes);
    EXPECT_EQ(runs, 0);
}

// Over RTU and ASCII the same cuts apply to the frame inside its CRC or LRC: each candidate is
// a whole frame a conforming reader takes (over RTU, a length the function code allows), and a
// frame broken on purpose is left alone.
TEST(Minimize, CutsRtuAndAsciiFramesKeepingTheirChecksums) {
    for (const codec::Framing framing : {codec::Framing::Rtu, codec::Framing::Ascii}) {
        // 0x64, a user-defined code: no length rule, so RTU readers end it at its CRC.
        const auto user =
            reframe(adu(0, {0x64, 0x12, 0x34, 0x00, 0x04, 0x08, 1, 2, 3, 4}), framing);
        const auto fc03 = reframe(adu(0, {0x03, 0, 0, 0, 1}), framing);
        const auto fc16 = reframe(adu(0, {0x10, 0, 0, 0, 1, 2, 0xAB, 0xCD}), framing);
        Case c;
        std::vector<std::uint8_t> all = fc03;
        all.insert(all.end(), user.begin(), user.end());
        all.insert(all.end(), fc16.begin(), fc16.end());
        c.steps.push_back(Step{Op::Send, 0, 0, 0, all});
        const Case small = minimize_case(
            c,
            [&](const Case& k) {
                bool user_fault = false, write_fault = false;
                for (const Step& st : k.steps) {
                    std::size_t used = 0;
                    const auto views = request_views(st.bytes, framing, used);
                    EXPECT_EQ(used, st.bytes.size());  // whole frames, checksums right
                    for (const auto& v : views) {
                        user_fault = user_fault || (v.size() >= 10 && v[7] == 0x64 &&
                                                    v[8] == 0x12 && v[9] == 0x34);
                        write_fault = write_fault || (v.size() >= 8 && v[7] == 0x10);
                    }
                }
                return user_fault && write_fault;
            },
            60, true, framing);
        ASSERT_EQ(small.steps.size(), 2u);
        EXPECT_EQ(small.steps[0].bytes, reframe(adu(0, {0x64, 0x12, 0x34}), framing));
        // FC16 says how long it is: over RTU only the whole frame is one; ASCII ends at its LF.
        EXPECT_EQ(small.steps[1].bytes,
                  framing == codec::Framing::Rtu ? fc16 : reframe(adu(0, {0x10}), framing));

        Case broken;
        auto bad = user;
        bad[bad.size() - (framing == codec::Framing::Rtu ? 1 : 3)] ^= 0x01;  // CRC / LRC digit
        broken.steps.push_back(Step{Op::Send, 0, 0, 0, bad});
        int runs = 0;
        const Case kept = minimize_case(
            broken,
            [&](const Case&) {
                ++runs;
                return true;
            },
            40, true, framing);
        EXPECT_EQ(kept.steps[0].bytes, bad);
        EXPECT_EQ(runs, 0);
    }
}

TEST(Finding, SaveLoadRoundTrip) {
    Finding f;
    f.verdict =
        Verdict{Oracle::Hang, "no-answer/fc03-valid", 0x03, "no answer", "an answer", "silence"};
    f.hits = 7;
    f.original_case.steps = {Step{Op::Send, 0, 0, 0, {9, 9}}};
    f.fuzz_case.cls = MutationClass::Split;
    f.fuzz_case.function = 0x03;
    f.fuzz_case.steps = {Step{Op::Send, 0, 0, 0, {1, 2, 3}}, Step{Op::Send, 0, 200, 0, {4, 5}},
                         Step{Op::ShutdownWrite, 1, 0, 0, {}}};
    f.profile = profile();
    f.profile.unsupported[0x14] = true;
    f.trace = {TraceEvent{5, 0, TraceKind::Send, {1, 2, 3}, ""}};
    const auto dir =
        (std::filesystem::temp_directory_path() / "mbstorm-finding-roundtrip").string();
    ASSERT_TRUE(save_finding(f, dir).ok());
    const Result<Finding> loaded = load_finding(dir);
    ASSERT_TRUE(loaded.ok()) << loaded.error().text();
    const Finding& g = *loaded;
    EXPECT_EQ(g.oracle(), Oracle::Hang);
    EXPECT_EQ(g.key(), "hang:no-answer/fc03-valid");
    EXPECT_EQ(g.function(), 0x03);
    EXPECT_EQ(g.hits, 7u);
    ASSERT_EQ(g.original_case.steps.size(), 1u);
    EXPECT_EQ(g.original_case.steps[0].bytes, (std::vector<std::uint8_t>{9, 9}));
    EXPECT_EQ(g.fuzz_case.cls, MutationClass::Split);
    ASSERT_EQ(g.fuzz_case.steps.size(), 3u);
    EXPECT_EQ(g.fuzz_case.steps[1].bytes, (std::vector<std::uint8_t>{4, 5}));
    EXPECT_EQ(g.fuzz_case.steps[1].delay_us, 200u);
    EXPECT_EQ(g.fuzz_case.steps[2].op, Op::ShutdownWrite);
    EXPECT_TRUE(g.profile.unsupported[0x14]);
    EXPECT_FALSE(g.profile.unsupported[0x13]);
    EXPECT_EQ(g.profile.probe_pdu, f.profile.probe_pdu);
    std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace mbstorm::netfuzz
