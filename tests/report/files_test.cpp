#include "report/files.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

namespace mbstorm::report {
namespace {

std::string temp_path(const char* name) {
    return ::testing::TempDir() + name + "_" + std::to_string(::getpid());
}

TEST(Files, WriteTextFileWritesTheContent) {
    const std::string path = temp_path("files_write");
    const Error error = write_text_file(path, "hello\n");
    ASSERT_TRUE(error.ok()) << error.text();
    std::ifstream in(path);
    std::stringstream text;
    text << in.rdbuf();
    EXPECT_EQ(text.str(), "hello\n");
    std::remove(path.c_str());
}

// A report that cannot be written is an Io error naming the path (the CLI prints its text).
TEST(Files, WriteTextFileIntoAMissingDirectoryIsAnIoError) {
    const Error error = write_text_file("/nonexistent-dir/report.json", "{}");
    EXPECT_EQ(error.code(), ErrorCode::Io);
    EXPECT_EQ(error.text(), "/nonexistent-dir/report.json: No such file or directory");
}

TEST(Files, CheckWritableSaysWhyAndLeavesNoFileBehind) {
    const std::string path = temp_path("files_check");
    EXPECT_TRUE(check_writable(path).ok());
    EXPECT_NE(::access(path.c_str(), F_OK), 0);  // created for the check, removed again
    const Error full = check_writable("/dev/full");
    EXPECT_EQ(full.code(), ErrorCode::Io);
    EXPECT_EQ(full.text(), "/dev/full: No space left on device");
    EXPECT_EQ(check_writable("/nonexistent-dir/x").code(), ErrorCode::Io);
}

TEST(Files, CloseStreamedFileReportsAnEarlierWriteFailure) {
    std::FILE* file = std::fopen(temp_path("files_close").c_str(), "w");
    ASSERT_NE(file, nullptr);
    errno = ENOSPC;
    const Error error = close_streamed_file(file, true);
    EXPECT_EQ(file, nullptr);
    EXPECT_EQ(error.code(), ErrorCode::Io);
    EXPECT_EQ(error.text(), "No space left on device");
    std::remove(temp_path("files_close").c_str());
    EXPECT_TRUE(close_streamed_file(file, false).ok());  // nothing open: nothing to report
}

}  // namespace
}  // namespace mbstorm::report
