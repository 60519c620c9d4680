// The one place an Error becomes an exit code and a line on stderr (cli/exit_codes.cpp).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "../support/run_mbstorm.hpp"
#include "cli/commands.hpp"

namespace mbstorm::cli {
namespace {

TEST(ExitCodes, EveryErrorKindExitsAsBadInputAndSuccessExitsZero) {
    EXPECT_EQ(exit_code_for(Error::none()), kExitOk);
    for (ErrorCode code :
         {ErrorCode::InvalidInput, ErrorCode::NotFound, ErrorCode::Io, ErrorCode::Network,
          ErrorCode::Unsupported, ErrorCode::Refused, ErrorCode::Interrupted}) {
        EXPECT_EQ(exit_code_for(Error(code, "x")), kExitUsage) << error_code_name(code);
    }
}

TEST(ExitCodes, FailSaysTheCommandThePlaceAndEachLine) {
    testing::internal::CaptureStderr();
    const int code =
        fail("run", Error(ErrorCode::InvalidInput, "first problem\nsecond problem", "s.yaml:3:5"));
    const std::string said = testing::internal::GetCapturedStderr();
    EXPECT_EQ(code, kExitUsage);
    EXPECT_EQ(said, "mbstorm run: s.yaml:3:5: first problem\nmbstorm run: second problem\n");

    testing::internal::CaptureStderr();
    EXPECT_EQ(usage_error("fuzz", "--seconds or --cases"), kExitUsage);
    EXPECT_EQ(testing::internal::GetCapturedStderr(), "mbstorm fuzz: --seconds or --cases\n");
}

// End to end: a scenario's YAML error reaches the user as "mbstorm run: FILE:LINE:COLUMN:
// message", once, and exits 2.
TEST(ExitCodes, AScenarioErrorReachesTheUserWithItsPlace) {
    const auto path = std::filesystem::path(::testing::TempDir()) / "mbstorm_bad_key.yaml";
    std::ofstream(path) << "operations: [{function: 3}]\nconections: 4\n";
    const auto r = test::run_mbstorm("run " + path.string() + " -q", 30);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_EQ(r.output.rfind("mbstorm run: " + path.string() + ":2:1: unknown key 'conections'", 0),
              0u)
        << r.output;
    std::filesystem::remove(path);
}

}  // namespace
}  // namespace mbstorm::cli
