// The codec never allocates: global operator new/delete are replaced in this binary with
// counting versions (forwarding to malloc/free), and millions of encode/decode calls over
// every function code run between two readings of the count.
#include <gtest/gtest.h>

#include "../support/counting_allocator.hpp"
#include "pdu_test_support.hpp"
#include "pdu_vectors.hpp"

namespace mbstorm::codec::test {
namespace {

// Allocations since construction (this binary is single-threaded while it counts).
class CountAllocations {
  public:
    std::uint64_t count() const { return mbstorm::testing::allocations() - start_; }

  private:
    std::uint64_t start_ = mbstorm::testing::allocations();
};

TEST(AllocCount, CounterSeesAllocations) {
    CountAllocations counter;
    int* volatile p = new int(3);  // volatile: the compiler may not elide the pair
    delete p;
    EXPECT_EQ(counter.count(), 1u);
}

TEST(AllocCount, EncodeAndDecodeNeverAllocate) {
    // Parse the vectors before counting starts.
    std::vector<ByteVec> requests;
    std::vector<ByteVec> responses;
    for (const char* h : kValidRequests) requests.push_back(hex(h));
    for (const char* h : kValidResponses) responses.push_back(hex(h));
    std::vector<ByteVec> broken = {hex("03 00 00 00 00"),
                                   hex("41"),
                                   hex("0F 00 00 00 0A 01 FF"),
                                   hex("14 07 05 00 01 00 00 00 01"),
                                   hex("2B 0D"),
                                   hex("")};

    std::uint8_t out[300];
    std::size_t ok = 0;
    std::size_t iterations = 0;
    {
        CountAllocations counter;
        // ~3 million codec calls.
        for (int round = 0; round < 12000; ++round) {
            for (const ByteVec& pdu : requests) {
                Request r;
                ok += decode_request(view(pdu), r).ok();
                ok += encode_request(r, MutableBytes(out, sizeof out)).ok();
                ok += encode_request(r, MutableBytes(out, sizeof out), true).ok();
                ok += encode_request(r, MutableBytes(out, 2)).ok();  // BufferTooSmall path
                ok += expected_read_byte_count(r) > 0;
                FileRecordIterator it(r.payload, r.function == 0x15);
                FileSubRequest sub;
                while (it.next(sub) == CodecError::Ok) ++ok;
                ++iterations;
            }
            for (const ByteVec& pdu : responses) {
                Response r;
                ok += decode_response(view(pdu), r) == CodecError::Ok;
                ok += encode_response(r, MutableBytes(out, sizeof out)).ok();
                DeviceIdObjectIterator it(r.function == 0x2B ? r.payload : Bytes{});
                DeviceIdObject o;
                while (it.next(o) == CodecError::Ok) ++ok;
                FileResponseIterator fit(r.function == 0x14 ? r.payload : Bytes{});
                FileSubResponse fs;
                while (fit.next(fs) == CodecError::Ok) ++ok;
                ++iterations;
            }
            for (const ByteVec& pdu : broken) {
                Request rq;
                Response rs;
                ok += decode_request(view(pdu), rq).ok();
                ok += decode_response(view(pdu), rs) == CodecError::Ok;
            }
            ok += encode_read_request(0x03, 0, 125, MutableBytes(out, sizeof out)).ok();
            ok += encode_exception(0x03, ExceptionCode::IllegalDataAddress,
                                   MutableBytes(out, sizeof out))
                      .ok();
        }
        EXPECT_EQ(counter.count(), 0u);
    }
    EXPECT_GT(iterations, 500000u);
    EXPECT_GT(ok, iterations);
}

}  // namespace
}  // namespace mbstorm::codec::test
