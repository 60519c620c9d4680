#include "cli/frame_describe.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace mbstorm::cli {
namespace {

std::vector<std::string> field_names(const std::vector<FieldRow>& rows) {
    std::vector<std::string> names;
    for (const auto& row : rows) names.push_back(row.field);
    return names;
}

// The specification's FC15 example (v1.1b3, 6.15): one sub-request writing three registers.
constexpr std::array<std::uint8_t, 15> kWriteFileRecord = {
    0x15, 0x0D, 0x06, 0x00, 0x04, 0x00, 0x07, 0x00, 0x03, 0x06, 0xAF, 0x04, 0xBE, 0x10, 0x0D};

TEST(FrameDescribe, WriteFileRecordResponseEchoesTheRequestRowForRow) {
    std::vector<FieldRow> request, response;
    ASSERT_TRUE(describe_pdu(kWriteFileRecord, Direction::Request, request).ok());
    ASSERT_TRUE(describe_pdu(kWriteFileRecord, Direction::Response, response).ok());
    EXPECT_EQ(field_names(request), field_names(response));
    const std::string table = render_rows(request);
    for (const char* row :
         {"Byte count", "Sub-req 1 reference type", "Sub-req 1 file number",
          "Sub-req 1 record number", "Sub-req 1 record length", "Sub-req 1 data"}) {
        EXPECT_NE(table.find(row), std::string::npos) << row << "\n" << table;
    }
    EXPECT_EQ(table.find("Unparsed"), std::string::npos) << table;
}

TEST(FrameDescribe, ReadFileRecordRequestHasNoDataRows) {
    // Spec 6.14 example: two sub-requests of a read.
    constexpr std::array<std::uint8_t, 16> pdu = {0x14, 0x0E, 0x06, 0x00, 0x04, 0x00, 0x01, 0x00,
                                                  0x02, 0x06, 0x00, 0x03, 0x00, 0x09, 0x00, 0x02};
    std::vector<FieldRow> rows;
    const Error error = describe_pdu(pdu, Direction::Request, rows);
    ASSERT_TRUE(error.ok()) << error.text();
    const std::string table = render_rows(rows);
    EXPECT_NE(table.find("Sub-req 2 record length"), std::string::npos) << table;
    EXPECT_EQ(table.find("data"), std::string::npos) << table;
}

}  // namespace
}  // namespace mbstorm::cli
