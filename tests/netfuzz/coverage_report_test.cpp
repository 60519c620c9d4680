// fuzz --coverage-report: the function list the runtime writes (coverage/mbstorm_coverage.c),
// addr2line's answers, which functions count as reached, and the report's lines.
#include <dlfcn.h>
#include <gtest/gtest.h>
#include <sys/shm.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

#include "netfuzz/coverage_map.hpp"
#include "netfuzz/coverage_report.hpp"

using namespace mbstorm::netfuzz;
using mbstorm::Error;
using mbstorm::ErrorCode;
using mbstorm::Result;

namespace {

bool contains(const std::string& text, const std::string& part) {
    return text.find(part) != std::string::npos;
}

}  // namespace

// Not inlined, not static: a symbol addr2line finds in this test's own binary.
extern "C" __attribute__((noinline)) int mbstorm_test_symbol_to_find(int x) {
    return x * 3 + 1;
}

TEST(CoverageReport, FunctionListKeepsEachFunctionOnceWithItsModule) {
    // The second "module /srv/plc" block: the target restarted and listed itself again.
    const std::string text =
        "module /srv/plc\n0x1a2b 17\n0x2000 40\nmodule /usr/lib/libx.so\n0x10 3\n"
        "module /srv/plc\n0x1a2b 17\n0x2000 40\n";
    Result<std::vector<FunctionEntry>> parsed = parse_function_entries(text);
    ASSERT_TRUE(parsed.ok()) << parsed.error().text();
    std::vector<FunctionEntry> entries = *parsed;
    ASSERT_EQ(entries.size(), 3u);
    EXPECT_EQ(entries[0].module, "/srv/plc");
    EXPECT_EQ(entries[0].offset, 0x1a2bu);
    EXPECT_EQ(entries[0].guard, 17u);
    EXPECT_EQ(entries[2].module, "/usr/lib/libx.so");
    EXPECT_EQ(entries[2].offset, 0x10u);
    EXPECT_EQ(entries[2].guard, 3u);

    parsed = parse_function_entries("");
    ASSERT_TRUE(parsed.ok());
    EXPECT_TRUE(parsed->empty());
}

TEST(CoverageReport, FunctionListRefusesALineNamed) {
    std::string error;
    for (const char* bad : {"0x10 3\n",                      // before any module
                            "module /a\n0x10\n",             // no guard
                            "module /a\n16 3\n",             // offset not hex
                            "module /a\n0x10 three\n",       // guard not a number
                            "module /a\n0x10 3 extra\n"}) {  // more than two fields
        error = parse_function_entries(bad).error().message();
        EXPECT_TRUE(contains(error, "line ")) << error;
    }
    EXPECT_TRUE(contains(error, "line 2")) << error;
}

TEST(CoverageReport, Addr2lineAnswersAreReadInPairs) {
    const std::string answer =
        "handle_request\n/src/server.c:42\n"
        "parse(char const*)\n/src/parse.cpp:7 (discriminator 3)\n"
        "??\n??:0\n"
        "stripped\n??:?\n";
    Result<std::vector<SourceLocation>> parsed = parse_addr2line(answer, 4);
    ASSERT_TRUE(parsed.ok()) << parsed.error().text();
    const std::vector<SourceLocation>& where = *parsed;
    ASSERT_EQ(where.size(), 4u);
    EXPECT_EQ(where[0].function, "handle_request");
    EXPECT_EQ(where[0].file, "/src/server.c");
    EXPECT_EQ(where[0].line, 42u);
    EXPECT_EQ(where[1].function, "parse(char const*)");
    EXPECT_EQ(where[1].file, "/src/parse.cpp");
    EXPECT_EQ(where[1].line, 7u);
    EXPECT_EQ(where[2].file, "??");
    EXPECT_EQ(where[2].line, 0u);
    EXPECT_EQ(where[3].function, "stripped");
    EXPECT_EQ(where[3].line, 0u);

    const std::string error = parse_addr2line("main\n/src/a.c:1\n", 2).error().message();
    EXPECT_TRUE(contains(error, "2 line(s) for 2 address(es)")) << error;
}

TEST(CoverageReport, ReportCountsAndSortsByFileAndLine) {
    const std::vector<UnreachedFunction> unreached = {
        {{"/srv/plc", 0x30, 9}, {"zeta", "/src/b.c", 5}},
        {{"/srv/plc", 0x20, 8}, {"alpha", "/src/b.c", 90}},
        {{"/srv/plc", 0x10, 7}, {"maintenance", "/src/a.c", 300}},
        {{"/usr/lib/libx.so", 0x44, 2}, {"??", "??", 0}},  // no debug info: last
    };
    const std::string report = format_coverage_report(unreached, 10);
    EXPECT_EQ(report,
              "6 of 10 functions reached; never reached: 4\n"
              "maintenance  /src/a.c:300\n"
              "zeta         /src/b.c:5\n"
              "alpha        /src/b.c:90\n"
              "??           /usr/lib/libx.so+0x44\n");
}

TEST(CoverageReport, ATargetWithoutPcTableIsNamedNotReported) {
    CoverageMap map;
    const Result<std::string> report = coverage_report("", map);
    EXPECT_EQ(report.error().code(), ErrorCode::Unsupported);
    EXPECT_TRUE(contains(report.error().message(), "built without pc-table"))
        << report.error().text();
}

TEST(CoverageReport, Addr2lineNamesAFunctionOfThisBinary) {
    Dl_info info{};
    ASSERT_NE(::dladdr(reinterpret_cast<void*>(&mbstorm_test_symbol_to_find), &info), 0);
    const auto offset = reinterpret_cast<std::uintptr_t>(&mbstorm_test_symbol_to_find) -
                        reinterpret_cast<std::uintptr_t>(info.dli_fbase);
    // Not /proc/self/exe: that would be addr2line's own.
    const std::string self = std::filesystem::read_symlink("/proc/self/exe").string();
    const Result<std::vector<SourceLocation>> where = symbolise(self, {offset});
    ASSERT_TRUE(where.ok()) << where.error().text();
    ASSERT_EQ(where->size(), 1u);
    EXPECT_EQ((*where)[0].function, "mbstorm_test_symbol_to_find");

    const Error error = symbolise("/nonexistent/module", {offset}).error();
    EXPECT_TRUE(contains(error.message(), "addr2line")) << error.text();
}

// A function counts as reached when its entry's cell was hit at any time: in a case, or
// between cases (the target's start-up, discovery), which clear() keeps before zeroing.
TEST(CoverageReport, ReachedKeepsEveryHitAcrossClears) {
    CoverageMap m;
    ASSERT_TRUE(m.create(1 << 12).ok());
    void* at = ::shmat(m.id(), nullptr, 0);
    ASSERT_NE(at, reinterpret_cast<void*>(-1));
    auto* target = static_cast<std::uint8_t*>(at);
    target[5] = 1;  // the target's start-up, before any case
    m.clear();
    target[9] = 3;  // a case, collected
    m.collect();
    m.clear();
    target[11] = 1;  // after the last clear: still in the map
    EXPECT_TRUE(m.reached(5));
    EXPECT_TRUE(m.reached(9));
    EXPECT_TRUE(m.reached(11));
    EXPECT_FALSE(m.reached(6));
    EXPECT_FALSE(m.reached(1 << 12));  // past the map
    ::shmdt(at);
}

TEST(CoverageReport, FunctionListFileIsNamedInTheEnvironmentAndRemoved) {
    std::string path;
    {
        FunctionListFile file;
        ASSERT_TRUE(file.create().ok());
        file.export_environment();
        path = file.path();
        EXPECT_EQ(std::string(std::getenv(kFunctionListVariable)), path);
        const Result<std::string> text = file.read();
        ASSERT_TRUE(text.ok()) << text.error().text();
        EXPECT_TRUE(text->empty());
    }
    EXPECT_EQ(::access(path.c_str(), F_OK), -1);
    ::unsetenv(kFunctionListVariable);
}
