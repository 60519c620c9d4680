// The kernel TLS probe answers the same every time and says why when there is no offload;
// the sentence reports print names the path actually taken (userspace OpenSSL).
#include <gtest/gtest.h>

#include "net/kernel_tls.hpp"

namespace mbstorm::net {
namespace {

TEST(KernelTls, ProbeIsCachedAndExplainsItself) {
    const KernelTls& first = kernel_tls();
    EXPECT_EQ(&first, &kernel_tls());
    if (!first.available) {
        EXPECT_NE(first.detail.find("TCP_ULP tls"), std::string::npos);
    }
    const std::string path = describe_tls_path();
    EXPECT_NE(path.find("OpenSSL in userspace"), std::string::npos) << path;
    if (!first.available) {
        EXPECT_NE(path.find(first.detail), std::string::npos) << path;
    }
}

}  // namespace
}  // namespace mbstorm::net
