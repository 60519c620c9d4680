// The two texts a new public function code needs besides the codec's table, which no compiler
// error points to: README.md's list of names and the fuzzing dictionary's fc_ entries. These
// tests point to them instead (docs/architecture.md, "A new public function code").
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <fstream>
#include <sstream>
#include <string>

#include "codec/function_code.hpp"

namespace mbstorm::codec {
namespace {

std::string source_file(const std::string& relative) {
    std::ifstream in(std::string(MBSTORM_SOURCE_DIR) + "/" + relative);
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
}

// README.md's "Function codes" section, up to the next heading.
std::string readme_function_codes() {
    const std::string readme = source_file("README.md");
    const auto start = readme.find("## Function codes");
    if (start == std::string::npos) return {};
    const auto end = readme.find("\n## ", start + 1);
    return readme.substr(start, end == std::string::npos ? std::string::npos : end - start);
}

TEST(FunctionTexts, ReadmeNamesEveryPublicFunctionCode) {
    const std::string section = readme_function_codes();
    ASSERT_FALSE(section.empty()) << "README.md has no '## Function codes' section";
    // The list wraps lines: compare with the line breaks and indentation as spaces.
    std::string flat;
    for (const char c : section) {
        if (c == '\n') {
            flat += ' ';
        } else if (!(c == ' ' && !flat.empty() && flat.back() == ' ')) {
            flat += c;
        }
    }
    for (const std::uint8_t fc : public_function_codes()) {
        const std::string entry = fmt::format("`{}` 0x{:02X}", function_name(fc), fc);
        EXPECT_NE(flat.find(entry), std::string::npos)
            << "README.md's 'Function codes' names lack " << entry;
    }
}

TEST(FunctionTexts, TheFuzzingDictionaryHasEveryPublicFunctionCode) {
    const std::string dict = source_file("fuzz/modbus.dict");
    ASSERT_FALSE(dict.empty()) << "fuzz/modbus.dict is missing";
    for (const std::uint8_t fc : public_function_codes()) {
        const std::string entry = fmt::format("fc_{}=\"\\x{:02X}\"", function_name(fc), fc);
        EXPECT_NE(dict.find(entry), std::string::npos) << "fuzz/modbus.dict lacks " << entry;
    }
}

}  // namespace
}  // namespace mbstorm::codec
