#include "util/error.hpp"

#include <gtest/gtest.h>

#include <cerrno>
#include <memory>
#include <string>

namespace mbstorm {
namespace {

TEST(Error, ADefaultErrorIsSuccess) {
    const Error e;
    EXPECT_TRUE(e.ok());
    EXPECT_EQ(e.code(), ErrorCode::Ok);
    EXPECT_EQ(e, Error::none());
}

TEST(Error, TextPutsThePlaceBeforeTheMessage) {
    EXPECT_EQ(Error(ErrorCode::InvalidInput, "unknown key 'rat'", "plan.yaml:3:5").text(),
              "plan.yaml:3:5: unknown key 'rat'");
    EXPECT_EQ(Error(ErrorCode::Io, "disk full").text(), "disk full");
}

TEST(Error, PrefixedSaysWhatTheCallerWasDoingAndKeepsTheCode) {
    Error e(ErrorCode::Network, "Connection refused");
    e.prefixed("cannot connect to 127.0.0.1:502");
    EXPECT_EQ(e.message(), "cannot connect to 127.0.0.1:502: Connection refused");
    EXPECT_EQ(e.code(), ErrorCode::Network);
    EXPECT_FALSE(e.ok());
}

TEST(Error, EveryCodeHasItsOwnName) {
    const ErrorCode codes[] = {ErrorCode::Ok,      ErrorCode::InvalidInput, ErrorCode::NotFound,
                               ErrorCode::Io,      ErrorCode::Network,      ErrorCode::Unsupported,
                               ErrorCode::Refused, ErrorCode::Interrupted};
    for (std::size_t i = 0; i < std::size(codes); ++i)
        for (std::size_t j = i + 1; j < std::size(codes); ++j)
            EXPECT_NE(error_code_name(codes[i]), error_code_name(codes[j]));
    EXPECT_EQ(error_code_name(ErrorCode::NotFound), "not found");
}

TEST(Error, FromErrnoNamesWhatFailedAndTheSystemsReason) {
    const Error e = from_errno(ErrorCode::Io, ENOENT, "out.json");
    EXPECT_EQ(e.code(), ErrorCode::Io);
    EXPECT_EQ(e.message(), "out.json: No such file or directory");
    EXPECT_EQ(from_errno(ErrorCode::Network, ECONNREFUSED, "").message(), "Connection refused");
}

Result<int> half(int n) {
    if (n % 2 != 0) return Error(ErrorCode::InvalidInput, "odd");
    return n / 2;
}

TEST(Error, AFileThatIsNotThereIsNotFoundAnyOtherOpenFailureIo) {
    EXPECT_EQ(open_failure("/nonexistent/mbstorm/none.yaml"), ErrorCode::NotFound);
    EXPECT_EQ(open_failure("/"), ErrorCode::Io);  // there, but a folder: not readable as a file
}

TEST(Result, HoldsAValueOrAnErrorNeverBoth) {
    const Result<int> good = half(8);
    ASSERT_TRUE(good.ok());
    EXPECT_EQ(*good, 4);
    EXPECT_TRUE(good.error().ok());
    const Result<int> bad = half(7);
    ASSERT_FALSE(bad.ok());
    EXPECT_EQ(bad.error().message(), "odd");
    EXPECT_EQ(bad.error().code(), ErrorCode::InvalidInput);
}

TEST(Result, MovesOutValuesThatCannotBeCopied) {
    Result<std::unique_ptr<int>> r = std::make_unique<int>(5);
    std::unique_ptr<int> p = std::move(r).value();
    ASSERT_NE(p, nullptr);
    EXPECT_EQ(*p, 5);
    Result<std::unique_ptr<int>> failed = Error(ErrorCode::NotFound, "gone");
    EXPECT_EQ(std::move(failed).error().message(), "gone");
}

}  // namespace
}  // namespace mbstorm
