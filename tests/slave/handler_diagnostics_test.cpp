// FC08 diagnostics, FC0B comm event counter, FC0C comm event log.
#include <gtest/gtest.h>

#include "slave_test_support.hpp"

namespace mbstorm::slave::test {
namespace {

using codec::ExceptionCode;

std::uint16_t counter(DataModel& m, unsigned sub) {
    const Reply r = call(m, Pdu(0x08).u16(sub).u16(0));
    EXPECT_EQ(r.result.outcome, Outcome::Response) << sub;
    EXPECT_EQ(r.bytes.size(), 5u);
    return codec::load_be16(r.bytes.data() + 3);
}

TEST(HandlerDiagnostics, ReturnQueryDataEchoesAnyLength) {
    DataModel m(small_config());
    const auto req = Pdu(0x08).u16(0).words({0xA537, 0x1234, 0x5678});
    const Reply r = call(m, req);
    EXPECT_EQ(r.bytes, req.bytes());
    EXPECT_EQ(r.decode_error, codec::CodecError::Ok);
    EXPECT_EQ(call(m, Pdu(0x08).u16(0)).bytes, Pdu(0x08).u16(0).bytes());
}

TEST(HandlerDiagnostics, CountersCountMessagesAndExceptions) {
    DataModel m(small_config());
    call(m, Pdu(0x03).u16(0).u16(1));
    call(m, Pdu(0x03).u16(500).u16(1));  // 02
    call(m, Pdu(0x63));                  // 01
    // This read is the 4th message and includes itself.
    EXPECT_EQ(counter(m, 0x0B), 4);  // bus message count
    EXPECT_EQ(counter(m, 0x0E), 5);  // server message count == bus message count over TCP
    EXPECT_EQ(counter(m, 0x0D), 2);  // bus exception error count
    EXPECT_EQ(counter(m, 0x0C), 0);  // comm errors: only the server notes framing errors
    EXPECT_EQ(counter(m, 0x0F), 0);  // no response
    EXPECT_EQ(counter(m, 0x10), 0);  // NAK
    EXPECT_EQ(counter(m, 0x11), 0);  // busy
    EXPECT_EQ(counter(m, 0x12), 0);  // overrun
    m.diagnostics().note_comm_error();
    m.diagnostics().note_busy();
    EXPECT_EQ(counter(m, 0x0C), 1);
    EXPECT_EQ(counter(m, 0x11), 1);
    EXPECT_EQ(counter(m, 0x02), 0);  // diagnostic register
}

TEST(HandlerDiagnostics, ClearCountersResetsEverything) {
    DataModel m(small_config());
    for (int i = 0; i < 5; ++i) call(m, Pdu(0x03).u16(500).u16(1));
    const auto clear = Pdu(0x08).u16(0x0A).u16(0);
    EXPECT_EQ(call(m, clear).bytes, clear.bytes());
    EXPECT_EQ(counter(m, 0x0D), 0);
    EXPECT_EQ(counter(m, 0x0B), 2);  // the clear itself is before the baseline; this read counts
    const Reply ev = call(m, Pdu(0x0B));
    EXPECT_EQ(codec::load_be16(ev.bytes.data() + 3), 2);  // the two counter reads since the clear
}

TEST(HandlerDiagnostics, RestartCommunicationsClearsCountersAndOptionallyTheLog) {
    DataModel m(small_config());
    call(m, Pdu(0x03).u16(500).u16(1));
    EXPECT_EQ(call(m, Pdu(0x08).u16(0x01).u16(0x0000)).result.outcome, Outcome::Response);
    EXPECT_EQ(counter(m, 0x0D), 0);
    // Log still has entries after a plain restart ...
    Reply log = call(m, Pdu(0x0C));
    EXPECT_GT(log.bytes[1], 6);
    // ... and none right after 0xFF00.
    EXPECT_EQ(call(m, Pdu(0x08).u16(0x01).u16(0xFF00)).result.outcome, Outcome::Response);
    log = call(m, Pdu(0x0C));
    EXPECT_EQ(log.bytes[1], 6);
    EXPECT_TRUE(
        call(m, Pdu(0x08).u16(0x01).u16(0x1234)).is_exception(ExceptionCode::IllegalDataValue));
}

TEST(HandlerDiagnostics, UnsupportedSubFunctionsAre01AndBadDataIs03) {
    DataModel m(small_config());
    EXPECT_TRUE(call(m, Pdu(0x08).u16(0x13).u16(0)).is_exception(ExceptionCode::IllegalFunction));
    EXPECT_TRUE(call(m, Pdu(0x08).u16(0x15).u16(0)).is_exception(ExceptionCode::IllegalFunction));
    // Serial-line only sub-functions.
    EXPECT_TRUE(
        call(m, Pdu(0x08).u16(0x03).u16(0x0A00)).is_exception(ExceptionCode::IllegalFunction));
    EXPECT_TRUE(call(m, Pdu(0x08).u16(0x04).u16(0)).is_exception(ExceptionCode::IllegalFunction));
    EXPECT_TRUE(call(m, Pdu(0x08).u16(0x0B).u16(1)).is_exception(ExceptionCode::IllegalDataValue));
    EXPECT_TRUE(call(m, Pdu(0x08).u16(0x0B)).is_exception(ExceptionCode::IllegalDataValue));
    const auto overrun = Pdu(0x08).u16(0x14).u16(0);
    EXPECT_EQ(call(m, overrun).bytes, overrun.bytes());
}

TEST(HandlerDiagnostics, CommEventCounterSkipsExceptionsAndFetches) {
    DataModel m(small_config());
    call(m, Pdu(0x06).u16(0).u16(1));
    call(m, Pdu(0x03).u16(0).u16(1));
    call(m, Pdu(0x03).u16(999).u16(1));  // exception: not counted
    Reply r = call(m, Pdu(0x0B));
    ASSERT_EQ(r.bytes.size(), 5u);
    EXPECT_EQ(codec::load_be16(r.bytes.data() + 1), 0x0000);  // status
    EXPECT_EQ(codec::load_be16(r.bytes.data() + 3), 2);
    r = call(m, Pdu(0x0B));  // fetching twice changes nothing
    EXPECT_EQ(codec::load_be16(r.bytes.data() + 3), 2);
    EXPECT_EQ(r.decode_error, codec::CodecError::Ok);
    EXPECT_EQ(r.decoded.event_count, 2);
}

TEST(HandlerDiagnostics, EventLogNewestFirst) {
    DataModel m(small_config());
    call(m, Pdu(0x03).u16(0).u16(1));    // receive 0x80, send 0x40
    call(m, Pdu(0x03).u16(999).u16(1));  // receive 0x80, send 0x41 (read exception 1-3)
    const Reply r = call(m, Pdu(0x0C));
    ASSERT_EQ(r.decode_error, codec::CodecError::Ok);
    ASSERT_EQ(r.bytes.size(), 8u + 4u);
    EXPECT_EQ(r.bytes[1], 10);                           // byte count
    EXPECT_EQ(codec::load_be16(r.bytes.data() + 4), 1);  // event count (one success)
    EXPECT_EQ(codec::load_be16(r.bytes.data() + 6), 3);  // message count incl. this one
    EXPECT_EQ(r.bytes[8], 0x41);
    EXPECT_EQ(r.bytes[9], 0x80);
    EXPECT_EQ(r.bytes[10], 0x40);
    EXPECT_EQ(r.bytes[11], 0x80);
}

TEST(HandlerDiagnostics, MessagesNotedInABatchCountAndLogAsIfOneByOne) {
    // A server notes the FC03/04 reads it answers inline once per frame loop (issue #18).
    DataModel m(small_config());
    call(m, Pdu(0x03).u16(999).u16(1));  // receive 0x80, send 0x41
    m.diagnostics().note_messages(2, kReceiveEvent, kSendEvent);
    Reply r = call(m, Pdu(0x0C));
    ASSERT_EQ(r.bytes.size(), 8u + 6u);
    EXPECT_EQ(codec::load_be16(r.bytes.data() + 6), 4);  // message count incl. this one
    EXPECT_EQ(codec::load_be16(r.bytes.data() + 4), 2);  // the two noted reads
    const std::vector<std::uint8_t> newest_first = {0x40, 0x80, 0x40, 0x80, 0x41, 0x80};
    EXPECT_EQ(std::vector<std::uint8_t>(r.bytes.begin() + 8, r.bytes.end()), newest_first);

    // More than the log holds: the newest 32 pairs, the count exact.
    call(m, Pdu(0x03).u16(999).u16(1));
    m.diagnostics().note_messages(31, kReceiveEvent, 0x42);  // wraps around the ring
    r = call(m, Pdu(0x0C));
    ASSERT_EQ(r.bytes.size(), 8u + 64u);
    for (std::size_t i = 8; i < 8 + 62; i += 2) EXPECT_EQ(r.bytes[i], 0x42) << i;
    EXPECT_EQ(r.bytes[8 + 62], 0x41);  // the exception before them
    m.diagnostics().note_messages(100, kReceiveEvent, kSendEvent);
    r = call(m, Pdu(0x0C));
    ASSERT_EQ(r.bytes.size(), 8u + 64u);
    EXPECT_EQ(codec::load_be16(r.bytes.data() + 6), 4 + 1 + 31 + 1 + 100 + 1);
    for (std::size_t i = 8; i < r.bytes.size(); i += 2) {
        EXPECT_EQ(r.bytes[i], 0x40) << i;
        EXPECT_EQ(r.bytes[i + 1], 0x80) << i;
    }
    m.diagnostics().note_messages(100, kReceiveEvent, kSendEvent);
    m.diagnostics().note_messages(1, kReceiveEvent, 0x42);
    r = call(m, Pdu(0x0C));
    ASSERT_EQ(r.bytes.size(), 8u + 64u);
    EXPECT_EQ(r.bytes[8], 0x42);
    EXPECT_EQ(r.bytes[10], 0x40);
}

TEST(HandlerDiagnostics, EventLogHoldsAtMost64Bytes) {
    DataModel m(small_config());
    for (int i = 0; i < 100; ++i) call(m, Pdu(0x06).u16(0).u16(static_cast<unsigned>(i)));
    const Reply r = call(m, Pdu(0x0C));
    EXPECT_EQ(r.bytes[1], 6 + 64);
    EXPECT_EQ(r.bytes.size(), 8u + 64u);
    EXPECT_EQ(r.decode_error, codec::CodecError::Ok);
}

TEST(HandlerDiagnostics, TrackingCanBeSwitchedOff) {
    ModelConfig c = small_config();
    c.track_diagnostics = false;
    DataModel m(c);
    call(m, Pdu(0x03).u16(999).u16(1));
    EXPECT_EQ(counter(m, 0x0B), 0);
    EXPECT_EQ(counter(m, 0x0D), 0);
    EXPECT_EQ(call(m, Pdu(0x0C)).bytes[1], 6);
}

}  // namespace
}  // namespace mbstorm::slave::test
