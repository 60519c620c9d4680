// fuzz --coverage-report: the target's functions no case reached. A target built with
// -fsanitize-coverage=trace-pc-guard,pc-table and mbstorm's runtime lists its functions, each
// as an offset in its module with the guard (map cell) of its entry block, in the file named
// by MBSTORM_COVERAGE_PCS (coverage/mbstorm_coverage.c); a function whose entry cell was never
// hit was never reached. addr2line (binutils) names them, one call per module.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "netfuzz/coverage_map.hpp"

namespace mbstorm::netfuzz {

inline constexpr const char* kFunctionListVariable = "MBSTORM_COVERAGE_PCS";

struct FunctionEntry {
    std::string module;        // the executable or shared object, as the target loaded it
    std::uint64_t offset = 0;  // the function's address relative to the module's load base
    std::uint32_t guard = 0;   // its entry block's cell in the coverage map
};

// Reads the runtime's list: "module PATH" lines, each followed by "0xOFFSET GUARD" lines. A
// restarted target appends the same lines again: each function is kept once. An InvalidInput
// error (naming the line) when a line is neither.
Result<std::vector<FunctionEntry>> parse_function_entries(std::string_view text);

struct SourceLocation {
    std::string function;  // "??" when the module has no symbol for it
    std::string file;      // "??" without debug info
    unsigned line = 0;     // 0: unknown
};

// addr2line -f -C output: two lines per address, the function, then FILE:LINE ("??:0" or
// "??:?" unknown; possibly followed by " (discriminator N)"). An InvalidInput error unless it
// holds exactly `addresses` pairs.
Result<std::vector<SourceLocation>> parse_addr2line(std::string_view text, std::size_t addresses);

// Names `offsets` of `module` with one addr2line run (NotFound: no addr2line on PATH).
Result<std::vector<SourceLocation>> symbolise(const std::string& module,
                                              const std::vector<std::uint64_t>& offsets);

struct UnreachedFunction {
    FunctionEntry entry;
    SourceLocation where;
};

// "N of M functions reached" and then "function  file:line" for each function never
// reached (MODULE+0xOFFSET without debug info), sorted by file and line.
std::string format_coverage_report(std::vector<UnreachedFunction> unreached, std::size_t total);

// The report for the list the target wrote (`list_text`) and what `map` saw reached. An Error
// when the list is empty (Unsupported: a target built without pc-table) or symbolising fails.
Result<std::string> coverage_report(std::string_view list_text, const CoverageMap& map);

// The file the target's runtime writes its list to: created empty in a new temporary folder,
// named in this process's environment (kFunctionListVariable) for the target command, removed
// with this object.
class FunctionListFile {
  public:
    FunctionListFile() = default;
    FunctionListFile(const FunctionListFile&) = delete;
    FunctionListFile& operator=(const FunctionListFile&) = delete;
    ~FunctionListFile();

    Error create();
    void export_environment() const;
    Result<std::string> read() const;
    const std::string& path() const noexcept { return path_; }

  private:
    std::string dir_, path_;
};

}  // namespace mbstorm::netfuzz
