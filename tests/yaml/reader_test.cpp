// The one YAML reader under both the device and the scenario parsers: positions, valid keys,
// duplicate keys, integer forms and ranges, all raised through the caller's own error type.
#include "yaml/reader.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

namespace mbstorm::yaml {
namespace {

struct TestError : std::runtime_error {
    TestError(const std::string& message, int l, int c)
        : std::runtime_error(message), line(l), column(c) {}
    int line;
    int column;
};

[[noreturn]] void raise_test_error(const std::string& message, int line, int column) {
    throw TestError(message, line, column);
}

const Reader kReader("doc.yaml", &raise_test_error);

// The error each_key raises for `text` with keys a and b known, or "" when it accepts it.
TestError each_key_error(const std::string& text) {
    try {
        kReader.each_key(YAML::Load(text), "thing", {"a", "b"},
                         [](const std::string&, const YAML::Node&, const YAML::Node&) {});
    } catch (const TestError& e) {
        return e;
    }
    return TestError("", 0, 0);
}

TEST(YamlReader, VisitsEveryKeyInOrder) {
    std::vector<std::string> seen;
    kReader.each_key(YAML::Load("b: 1\na: 2\n"), "thing", {"a", "b"},
                     [&](const std::string& key, const YAML::Node&, const YAML::Node& value) {
                         seen.push_back(key + "=" + value.Scalar());
                     });
    EXPECT_EQ(seen, (std::vector<std::string>{"b=1", "a=2"}));
}

TEST(YamlReader, UnknownKeyNamesTheValidKeysAndThePosition) {
    const TestError e = each_key_error("a: 1\nc: 2\n");
    EXPECT_STREQ(e.what(), "doc.yaml:2:1: unknown key 'c' in thing (valid keys: a, b)");
    EXPECT_EQ(e.line, 2);
    EXPECT_EQ(e.column, 1);
}

TEST(YamlReader, UnknownKeyNearAValidOneSuggestsItInsteadOfTheList) {
    const TestError e = each_key_error("a: 1\nbb: 2\n");
    EXPECT_STREQ(e.what(), "doc.yaml:2:1: unknown key 'bb' in thing; did you mean 'b'?");
}

TEST(YamlReader, DuplicateKeyIsRejected) {
    const TestError e = each_key_error("a: 1\nb: 2\na: 3\n");
    EXPECT_STREQ(e.what(), "doc.yaml:3:1: duplicate key 'a' in thing");
    EXPECT_EQ(e.line, 3);
}

TEST(YamlReader, NonMappingAndNonScalarKeysAreRejected) {
    EXPECT_NE(std::string(each_key_error("- 1\n").what()).find("thing must be a mapping"),
              std::string::npos);
    EXPECT_NE(std::string(each_key_error("[1]: 2\n").what()).find("keys must be plain words"),
              std::string::npos);
}

TEST(YamlReader, IntegersInDecimalHexAndBinary) {
    std::int64_t v = 0;
    ASSERT_TRUE(Reader::parse_integer("42", v));
    EXPECT_EQ(v, 42);
    ASSERT_TRUE(Reader::parse_integer("-0x10", v));
    EXPECT_EQ(v, -16);
    ASSERT_TRUE(Reader::parse_integer("0b101", v));
    EXPECT_EQ(v, 5);
    ASSERT_TRUE(Reader::parse_integer("+0B11", v));
    EXPECT_EQ(v, 3);
    for (const char* bad :
         {"", "-", "0x", "0b", "0b2", "12a", "1.5", "0x1g", "99999999999999999999"}) {
        EXPECT_FALSE(Reader::parse_integer(bad, v)) << bad;
    }
    EXPECT_EQ(kReader.integer(YAML::Load("0b1111"), "n", 0, 15), 15);
}

TEST(YamlReader, IntegerErrorsGiveTheValidRange) {
    try {
        kReader.integer(YAML::Load("x: 300")["x"], "unit", 0, 255);
        FAIL();
    } catch (const TestError& e) {
        EXPECT_STREQ(e.what(), "doc.yaml:1:4: unit: 300 is out of range (valid 0..255)");
    }
    try {
        kReader.integer(YAML::Load("many"), "unit", 0, 255);
        FAIL();
    } catch (const TestError& e) {
        EXPECT_NE(std::string(e.what()).find("'many' is not a whole number (valid 0..255)"),
                  std::string::npos);
    }
    EXPECT_THROW(kReader.integer(YAML::Load("[1]"), "unit", 0, 255), TestError);
}

TEST(YamlReader, NumbersBooleansAndChoices) {
    EXPECT_DOUBLE_EQ(kReader.number(YAML::Load("+1.5e3"), "n"), 1500.0);
    EXPECT_DOUBLE_EQ(kReader.number(YAML::Load("0x10"), "n"), 16.0);
    EXPECT_THROW(kReader.number(YAML::Load("inf"), "n"), TestError);
    EXPECT_THROW(kReader.number(YAML::Load("2"), "n", 0, 1), TestError);
    EXPECT_TRUE(kReader.boolean(YAML::Load("Yes"), "b"));
    EXPECT_FALSE(kReader.boolean(YAML::Load("off"), "b"));
    EXPECT_THROW(kReader.boolean(YAML::Load("maybe"), "b"), TestError);
    EXPECT_EQ(kReader.choice(YAML::Load("fast"), "c", {"slow", "fast"}), "fast");
    EXPECT_THROW(kReader.choice(YAML::Load("medium"), "c", {"slow", "fast"}), TestError);
}

// The printers write through yaml-cpp's emitter, which turns bytes that are not UTF-8 into
// U+FFFD: such text is refused where it is read, not changed where it is printed.
TEST(YamlReader, TextThatIsNotUtf8IsRefused) {
    EXPECT_EQ(kReader.scalar(YAML::Load("\"caf\xC3\xA9 \xE2\x82\xAC \xF0\x9F\x98\x80\""), "s"),
              "caf\xC3\xA9 \xE2\x82\xAC \xF0\x9F\x98\x80");
    for (const char* bad : {"'a\xFF'", "'\xC0\xAF'", "'\xED\xA0\x80'", "'\xE2\x82'",
                            "'\xF4\x90\x80\x80'", "'\x80'"}) {
        try {
            (void)kReader.scalar(YAML::Load(bad), "vendor_name");
            ADD_FAILURE() << "accepted " << bad;
        } catch (const TestError& e) {
            EXPECT_NE(std::string(e.what()).find("vendor_name is not UTF-8 text"),
                      std::string::npos)
                << e.what();
        }
    }
}

}  // namespace
}  // namespace mbstorm::yaml
