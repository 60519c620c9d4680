// The ClientHello the fuzzer sends where TLS is not spoken: a whole record, the same bytes at
// every call (a fuzz run with a seed must repeat: a coverage build's corpus takes this case in).
#include <gtest/gtest.h>

#include "net/tls_hello.hpp"

namespace mbstorm::net {
namespace {

void expect_one_record(const std::vector<std::uint8_t>& hello) {
    ASSERT_GT(hello.size(), 5u);
    EXPECT_EQ(hello[0], 0x16);  // handshake
    EXPECT_EQ(hello[1], 0x03);
    EXPECT_EQ(static_cast<std::size_t>(hello[3] << 8 | hello[4]) + 5, hello.size());
    EXPECT_EQ(hello[5], 0x01);  // ClientHello
}

TEST(TlsHello, IsOneClientHelloRecordWithTheSameBytesEveryTime) {
    for (const bool tls12 : {false, true}) {
        const auto first = tls_client_hello(tls12);
        expect_one_record(first);
        for (int i = 0; i < 3; ++i) EXPECT_EQ(tls_client_hello(tls12), first) << tls12;
    }
    // TLS 1.3 offers a key share: it is fixed too, and the hello is longer than 1.2's.
    EXPECT_GT(tls_client_hello(false).size(), tls_client_hello(true).size());
}

}  // namespace
}  // namespace mbstorm::net
