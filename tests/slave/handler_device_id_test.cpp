// FC2B/0E Read Device Identification: categories, stream restart, individual access, more-follows.
#include <gtest/gtest.h>

#include <map>
#include <string>

#include "slave_test_support.hpp"

namespace mbstorm::slave::test {
namespace {

using codec::ExceptionCode;

struct DeviceIdReply {
    std::uint8_t code = 0, conformity = 0, more_follows = 0, next_object = 0, count = 0;
    std::map<std::uint8_t, std::string> objects;
    std::vector<std::uint8_t> order;
};

DeviceIdReply read_id(DataModel& m, unsigned code, unsigned object) {
    const Reply r = call(m, Pdu(0x2B).u8(0x0E).u8(code).u8(object));
    DeviceIdReply d;
    EXPECT_EQ(r.result.outcome, Outcome::Response);
    EXPECT_EQ(r.decode_error, codec::CodecError::Ok);
    if (r.bytes.size() < 7) return d;
    EXPECT_LE(r.bytes.size(), 253u);
    d.code = r.bytes[2];
    d.conformity = r.bytes[3];
    d.more_follows = r.bytes[4];
    d.next_object = r.bytes[5];
    d.count = r.bytes[6];
    codec::DeviceIdObjectIterator it(codec::Bytes(r.bytes).subspan(7));
    codec::DeviceIdObject obj;
    while (it.next(obj) == codec::CodecError::Ok) {
        d.objects[obj.id] = std::string(obj.value.begin(), obj.value.end());
        d.order.push_back(obj.id);
    }
    EXPECT_EQ(d.order.size(), d.count);
    return d;
}

TEST(HandlerDeviceId, BasicStreamHasTheThreeMandatoryObjects) {
    DataModel m(small_config());
    const DeviceIdReply d = read_id(m, 1, 0);
    EXPECT_EQ(d.code, 1);
    EXPECT_EQ(d.order, (std::vector<std::uint8_t>{0, 1, 2}));
    EXPECT_EQ(d.objects.at(0), "mbstorm");
    EXPECT_EQ(d.more_follows, 0x00);
    EXPECT_EQ(d.next_object, 0x00);
    EXPECT_EQ(d.conformity, 0x82);  // regular objects present by default
}

TEST(HandlerDeviceId, RegularStreamCoversZeroToSix) {
    DataModel m(small_config());
    EXPECT_EQ(read_id(m, 2, 0).order, (std::vector<std::uint8_t>{0, 1, 2, 3, 4, 5, 6}));
    // Starting inside the category continues from there.
    EXPECT_EQ(read_id(m, 2, 4).order, (std::vector<std::uint8_t>{4, 5, 6}));
}

TEST(HandlerDeviceId, UnknownOrOutOfCategoryObjectRestartsStreamAtZero) {
    DataModel m(small_config());
    EXPECT_EQ(read_id(m, 1, 5).order, (std::vector<std::uint8_t>{0, 1, 2}));
    EXPECT_EQ(read_id(m, 2, 0x42).order.front(), 0);
    EXPECT_EQ(read_id(m, 3, 0x90).order.front(), 0);  // no extended object 0x90 configured
}

TEST(HandlerDeviceId, ExtendedStreamIncludesPrivateObjects) {
    ModelConfig c = small_config();
    ASSERT_TRUE(c.identity.set(0x80, "serial 42"));
    ASSERT_TRUE(c.identity.set(0x95, "x"));
    ASSERT_FALSE(c.identity.set(0x10, "reserved ids are refused"));
    DataModel m(c);
    const DeviceIdReply d = read_id(m, 3, 0);
    EXPECT_EQ(d.conformity, 0x83);
    EXPECT_EQ(d.order, (std::vector<std::uint8_t>{0, 1, 2, 3, 4, 5, 6, 0x80, 0x95}));
    EXPECT_EQ(d.objects.at(0x80), "serial 42");
    EXPECT_EQ(read_id(m, 3, 0x95).order, (std::vector<std::uint8_t>{0x95}));
}

TEST(HandlerDeviceId, IndividualAccess) {
    DataModel m(small_config());
    const DeviceIdReply d = read_id(m, 4, 3);
    EXPECT_EQ(d.order, (std::vector<std::uint8_t>{3}));
    EXPECT_EQ(d.more_follows, 0);
    EXPECT_TRUE(
        call(m, Pdu(0x2B).u8(0x0E).u8(4).u8(0x80)).is_exception(ExceptionCode::IllegalDataAddress));
    EXPECT_TRUE(
        call(m, Pdu(0x2B).u8(0x0E).u8(4).u8(0x07)).is_exception(ExceptionCode::IllegalDataAddress));
}

TEST(HandlerDeviceId, AbsentRegularObjectsAreSkippedAndLowerTheConformity) {
    ModelConfig c = small_config();
    for (std::uint8_t id = 3; id <= 6; ++id) c.identity.set(id, "");
    DataModel m(c);
    const DeviceIdReply d = read_id(m, 2, 0);
    EXPECT_EQ(d.order, (std::vector<std::uint8_t>{0, 1, 2}));
    EXPECT_EQ(d.conformity, 0x81);
    EXPECT_TRUE(
        call(m, Pdu(0x2B).u8(0x0E).u8(4).u8(5)).is_exception(ExceptionCode::IllegalDataAddress));
}

TEST(HandlerDeviceId, LongObjectsForceMoreFollowsAndResumeFromNextObject) {
    ModelConfig c = small_config();
    // Objects 0-3 take 65 bytes after the 7-byte header; 4 adds 152 (224), 5 would add 102.
    c.identity.set(DeviceIdentity::kProductName, std::string(150, 'P'));  // object 4
    c.identity.set(DeviceIdentity::kModelName, std::string(100, 'M'));    // object 5
    DataModel m(c);
    const DeviceIdReply first = read_id(m, 2, 0);
    EXPECT_EQ(first.more_follows, 0xFF);
    EXPECT_EQ(first.next_object, 5);
    EXPECT_EQ(first.order, (std::vector<std::uint8_t>{0, 1, 2, 3, 4}));
    const DeviceIdReply second = read_id(m, 2, first.next_object);
    EXPECT_EQ(second.more_follows, 0x00);
    EXPECT_EQ(second.next_object, 0x00);
    EXPECT_EQ(second.order, (std::vector<std::uint8_t>{5, 6}));
    EXPECT_EQ(second.objects.at(5), std::string(100, 'M'));
}

TEST(HandlerDeviceId, LongestAllowedObjectFitsAlone) {
    ModelConfig c = small_config();
    ASSERT_TRUE(c.identity.set(0x80, std::string(DeviceIdentity::kMaxObjectLength, 'E')));
    ASSERT_FALSE(c.identity.set(0x81, std::string(DeviceIdentity::kMaxObjectLength + 1, 'E')));
    DataModel m(c);
    const Reply r = call(m, Pdu(0x2B).u8(0x0E).u8(4).u8(0x80));
    EXPECT_EQ(r.bytes.size(), 253u);
    const DeviceIdReply d = read_id(m, 3, 0x80);
    EXPECT_EQ(d.order, (std::vector<std::uint8_t>{0x80}));
}

TEST(HandlerDeviceId, BadCodeIs03AndOtherMeiTypesAre01) {
    DataModel m(small_config());
    EXPECT_TRUE(
        call(m, Pdu(0x2B).u8(0x0E).u8(0).u8(0)).is_exception(ExceptionCode::IllegalDataValue));
    EXPECT_TRUE(
        call(m, Pdu(0x2B).u8(0x0E).u8(5).u8(0)).is_exception(ExceptionCode::IllegalDataValue));
    EXPECT_TRUE(
        call(m, Pdu(0x2B).u8(0x0D).u8(0).u8(0)).is_exception(ExceptionCode::IllegalFunction));
}

}  // namespace
}  // namespace mbstorm::slave::test
