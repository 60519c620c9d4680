#include "netfuzz/coverage_report.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/mman.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <tuple>
#include <utility>

#include <fmt/format.h>
#include <fmt/ranges.h>

extern char** environ;

namespace mbstorm::netfuzz {
namespace {

constexpr std::string_view kModulePrefix = "module ";

// "0x1a2b 17": a function's offset in its module (hex) and its entry guard (decimal).
bool parse_function_line(std::string_view line, std::uint64_t& offset, std::uint32_t& guard) {
    if (line.substr(0, 2) != "0x") return false;
    const char* end = line.data() + line.size();
    auto [p, ec] = std::from_chars(line.data() + 2, end, offset, 16);
    if (ec != std::errc() || p == line.data() + 2 || p == end || *p != ' ') return false;
    auto [q, ec2] = std::from_chars(p + 1, end, guard);
    return ec2 == std::errc() && q == end && q != p + 1;
}

// Splits `text` into lines (the last one may lack its newline).
std::vector<std::string_view> lines_of(std::string_view text) {
    std::vector<std::string_view> lines;
    while (!text.empty()) {
        const std::size_t nl = text.find('\n');
        lines.push_back(text.substr(0, nl));
        if (nl == std::string_view::npos) break;
        text.remove_prefix(nl + 1);
    }
    return lines;
}

// "file.c:12", "file.c:12 (discriminator 3)" (the number ends at the space), "??:0", "??:?".
SourceLocation parse_location(std::string_view function, std::string_view text) {
    SourceLocation where{std::string(function), "??", 0};
    const std::size_t colon = text.rfind(':');
    if (colon == std::string_view::npos) return where;
    where.file = std::string(text.substr(0, colon));
    const std::string_view number = text.substr(colon + 1);
    std::from_chars(number.data(), number.data() + number.size(), where.line);
    return where;
}

}  // namespace

Result<std::vector<FunctionEntry>> parse_function_entries(std::string_view text) {
    std::vector<FunctionEntry> out;
    std::set<std::pair<std::string, std::uint64_t>> seen;
    std::string module;
    std::size_t number = 0;
    for (const std::string_view line : lines_of(text)) {
        ++number;
        if (line.substr(0, kModulePrefix.size()) == kModulePrefix) {
            module = std::string(line.substr(kModulePrefix.size()));
            continue;
        }
        FunctionEntry e{module, 0, 0};
        if (module.empty() || !parse_function_line(line, e.offset, e.guard)) {
            return Error(ErrorCode::InvalidInput,
                         fmt::format("line {} of the target's function list is not '{}PATH' or "
                                     "'0xOFFSET GUARD' after one: '{}'",
                                     number, kModulePrefix, line));
        }
        if (seen.emplace(module, e.offset).second) out.push_back(std::move(e));
    }
    return out;
}

Result<std::vector<SourceLocation>> parse_addr2line(std::string_view text, std::size_t addresses) {
    const std::vector<std::string_view> lines = lines_of(text);
    if (lines.size() != 2 * addresses) {
        return Error(ErrorCode::InvalidInput,
                     fmt::format("addr2line answered {} line(s) for {} address(es), not two each",
                                 lines.size(), addresses));
    }
    std::vector<SourceLocation> out;
    for (std::size_t i = 0; i < addresses; ++i)
        out.push_back(parse_location(lines[2 * i], lines[2 * i + 1]));
    return out;
}

namespace {

// A file in memory holding `text`, read from its start: a child's stdin.
int memory_file(const std::string& text) {
    const int fd = ::memfd_create("mbstorm-addresses", MFD_CLOEXEC);
    if (fd < 0) return -1;
    for (std::size_t done = 0; done < text.size();) {
        const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
        if (n <= 0) {
            ::close(fd);
            return -1;
        }
        done += static_cast<std::size_t>(n);
    }
    ::lseek(fd, 0, SEEK_SET);
    return fd;
}

// Runs `argv` (found on PATH) with `input` as its stdin; its stdout is `output`. Its stderr
// stays mbstorm's. An Error unless it ran and exited 0.
Error run_filter(const std::vector<std::string>& argv, const std::string& input,
                 std::string& output) {
    const int in = memory_file(input);
    int out[2];
    if (in < 0 || ::pipe2(out, O_CLOEXEC) != 0) {
        Error error(ErrorCode::Io, fmt::format("cannot run {}: {}", argv[0], std::strerror(errno)));
        if (in >= 0) ::close(in);
        return error;
    }
    posix_spawn_file_actions_t actions;
    ::posix_spawn_file_actions_init(&actions);
    ::posix_spawn_file_actions_adddup2(&actions, in, STDIN_FILENO);
    ::posix_spawn_file_actions_adddup2(&actions, out[1], STDOUT_FILENO);
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    pid_t pid = 0;
    const int spawned =
        ::posix_spawnp(&pid, argv[0].c_str(), &actions, nullptr, args.data(), environ);
    ::posix_spawn_file_actions_destroy(&actions);
    ::close(in);
    ::close(out[1]);
    if (spawned != 0) {
        ::close(out[0]);
        return Error(spawned == ENOENT ? ErrorCode::NotFound : ErrorCode::Io,
                     fmt::format("cannot run {}: {}", argv[0], std::strerror(spawned)));
    }
    char buffer[65536];
    for (ssize_t n; (n = ::read(out[0], buffer, sizeof buffer)) != 0;) {
        if (n > 0)
            output.append(buffer, static_cast<std::size_t>(n));
        else if (errno != EINTR)
            break;
    }
    ::close(out[0]);
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return Error::none();
    return Error(
        ErrorCode::Io,
        WIFEXITED(status)
            ? fmt::format("{} failed (exit {})", fmt::join(argv, " "), WEXITSTATUS(status))
            : fmt::format("{} was killed (signal {})", fmt::join(argv, " "), WTERMSIG(status)));
}

// Where a function is: FILE:LINE, or MODULE+0xOFFSET without debug info.
std::string location_text(const UnreachedFunction& f) {
    if (f.where.file == "??") return fmt::format("{}+0x{:x}", f.entry.module, f.entry.offset);
    return f.where.line ? fmt::format("{}:{}", f.where.file, f.where.line) : f.where.file;
}

}  // namespace

Result<std::vector<SourceLocation>> symbolise(const std::string& module,
                                              const std::vector<std::uint64_t>& offsets) {
    std::string addresses;
    for (const std::uint64_t o : offsets) addresses += fmt::format("0x{:x}\n", o);
    std::string answer;
    // binutils' addr2line: present wherever g++ is (llvm-symbolizer would need LLVM).
    if (Error e = run_filter({"addr2line", "-f", "-C", "-e", module}, addresses, answer); !e.ok())
        return e;
    return parse_addr2line(answer, offsets.size());
}

std::string format_coverage_report(std::vector<UnreachedFunction> unreached, std::size_t total) {
    // Those without debug info last, by module and offset.
    auto key = [](const UnreachedFunction& f) {
        return std::tuple(f.where.file == "??", f.where.file, f.where.line, f.entry.module,
                          f.entry.offset);
    };
    std::sort(unreached.begin(), unreached.end(),
              [&](const auto& a, const auto& b) { return key(a) < key(b); });
    std::size_t width = 0;
    for (const auto& f : unreached) width = std::max(width, f.where.function.size());
    std::string s = fmt::format("{} of {} functions reached; never reached: {}\n",
                                total - unreached.size(), total, unreached.size());
    for (const auto& f : unreached)
        s += fmt::format("{:<{}}  {}\n", f.where.function, width, location_text(f));
    return s;
}

Result<std::string> coverage_report(std::string_view list_text, const CoverageMap& map) {
    Result<std::vector<FunctionEntry>> parsed = parse_function_entries(list_text);
    if (!parsed.ok()) return std::move(parsed).error();
    const std::vector<FunctionEntry>& entries = *parsed;
    if (entries.empty()) {
        return Error(ErrorCode::Unsupported,
                     "the target was built without pc-table: it listed no functions (build it "
                     "with clang -fsanitize-coverage=trace-pc-guard,trace-cmp,pc-table and "
                     "mbstorm's runtime, coverage/mbstorm_coverage.c; AFL++'s compilers list "
                     "none)");
    }
    std::map<std::string, std::vector<const FunctionEntry*>> unreached_by_module;
    for (const FunctionEntry& e : entries)
        if (!map.reached(e.guard)) unreached_by_module[e.module].push_back(&e);
    std::vector<UnreachedFunction> unreached;
    for (const auto& [module, list] : unreached_by_module) {
        std::vector<std::uint64_t> offsets;
        for (const FunctionEntry* e : list) offsets.push_back(e->offset);
        Result<std::vector<SourceLocation>> where = symbolise(module, offsets);
        if (!where.ok()) return std::move(where).error();
        for (std::size_t i = 0; i < list.size(); ++i) unreached.push_back({*list[i], (*where)[i]});
    }
    return format_coverage_report(std::move(unreached), entries.size());
}

FunctionListFile::~FunctionListFile() {
    std::error_code ignored;
    if (!dir_.empty()) std::filesystem::remove_all(dir_, ignored);
}

Error FunctionListFile::create() {
    const char* tmp = std::getenv("TMPDIR");
    std::string pattern = std::string(tmp && *tmp ? tmp : "/tmp") + "/mbstorm-functions-XXXXXX";
    if (!::mkdtemp(pattern.data())) {
        return Error(ErrorCode::Io,
                     fmt::format("cannot create a folder for the target's function list ({}): {}",
                                 pattern, std::strerror(errno)));
    }
    dir_ = pattern;
    path_ = dir_ + "/functions.txt";
    if (!std::ofstream(path_)) return Error(ErrorCode::Io, fmt::format("cannot create {}", path_));
    return Error::none();
}

void FunctionListFile::export_environment() const {
    ::setenv(kFunctionListVariable, path_.c_str(), 1);
}

Result<std::string> FunctionListFile::read() const {
    std::ifstream in(path_, std::ios::binary);
    if (!in) {
        return Error(ErrorCode::Io,
                     fmt::format("cannot read the target's function list {}", path_));
    }
    std::ostringstream all;
    all << in.rdbuf();
    return all.str();
}

}  // namespace mbstorm::netfuzz
