// seccomp_run: runs a program under a seccomp filter, as a container runtime would, so the tests
// can show what mbstorm does where Docker, containerd or a "restricted" Kubernetes pod blocks
// io_uring (issue #32) without a container engine on the machine.
//
//   seccomp_run --deny-io-uring -- PROG ARGS...
//       every call allowed but io_uring_setup, io_uring_enter and io_uring_register, which fail
//       with EPERM: the errno Docker's default profile returns for a call it denies
//       (defaultErrnoRet 1).
//   seccomp_run --profile FILE.json -- PROG ARGS...
//       an OCI/Docker-format profile: defaultAction, defaultErrnoRet and syscalls[] (names,
//       action, errnoRet, args, includes, excludes), read as runc reads it for a container on
//       x86_64 that holds no capabilities (a restricted pod drops ALL):
//         - an entry with includes.caps is skipped (it grants a call to a capability we lack);
//           excludes.caps is always met;
//         - includes.arches / excludes.arches are matched against amd64 and x86_64;
//           includes.minKernel against this kernel's release;
//         - args become libseccomp comparisons (MASKED_EQ: value is the mask, valueTwo the
//           datum); conditions on one argument index only are ANDed in one rule, several on the
//           same index become one rule each (ORed), as runc does;
//         - names this libseccomp does not know are skipped (as runc does), and so is an entry
//           whose action is the default action;
//         - only the native architecture is in the filter: archMap is ignored, so a call made
//           through the i386 or x32 ABI is killed (libseccomp's default for a foreign arch).
//
// Exit status: PROG's own (it is exec'd in place of this process); 2 on a usage error; 125 when
// the profile cannot be read or the filter not loaded (as `docker run` exits 125 when it cannot
// start the container); 126 when PROG cannot be executed, 127 when it is not found.
#include <seccomp.h>
#include <sys/utsname.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace {
using nlohmann::json;

constexpr const char* kIoUringCalls[] = {"io_uring_setup", "io_uring_enter", "io_uring_register"};
constexpr int kLaunchFailed = 125;

struct LaunchError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

using Filter = std::unique_ptr<void, decltype(&seccomp_release)>;

Filter new_filter(std::uint32_t default_action) {
    Filter filter(seccomp_init(default_action), &seccomp_release);
    if (!filter) throw LaunchError("seccomp_init failed");
    return filter;
}

void add_rule(const Filter& filter, std::uint32_t action, const std::string& name,
              const std::vector<scmp_arg_cmp>& args) {
    int number = seccomp_syscall_resolve_name(name.c_str());
    // A call newer than this libseccomp: no process here can make it by name either.
    if (number == __NR_SCMP_ERROR) return;
    int rc = seccomp_rule_add_array(filter.get(), action, number,
                                    static_cast<unsigned>(args.size()), args.data());
    if (rc < 0) throw LaunchError("rule for " + name + ": " + std::strerror(-rc));
}

Filter deny_io_uring_filter() {
    Filter filter = new_filter(SCMP_ACT_ALLOW);
    for (const char* name : kIoUringCalls) add_rule(filter, SCMP_ACT_ERRNO(EPERM), name, {});
    return filter;
}

std::uint32_t action_named(const std::string& name, int errno_ret) {
    if (name == "SCMP_ACT_ALLOW") return SCMP_ACT_ALLOW;
    if (name == "SCMP_ACT_ERRNO") return SCMP_ACT_ERRNO(errno_ret);
    if (name == "SCMP_ACT_KILL" || name == "SCMP_ACT_KILL_THREAD") return SCMP_ACT_KILL_THREAD;
    if (name == "SCMP_ACT_KILL_PROCESS") return SCMP_ACT_KILL_PROCESS;
    if (name == "SCMP_ACT_TRAP") return SCMP_ACT_TRAP;
    if (name == "SCMP_ACT_LOG") return SCMP_ACT_LOG;
    throw LaunchError("unsupported action " + name);
}

scmp_compare comparison_named(const std::string& name) {
    static const std::pair<const char*, scmp_compare> kNames[] = {
        {"SCMP_CMP_NE", SCMP_CMP_NE},
        {"SCMP_CMP_LT", SCMP_CMP_LT},
        {"SCMP_CMP_LE", SCMP_CMP_LE},
        {"SCMP_CMP_EQ", SCMP_CMP_EQ},
        {"SCMP_CMP_GE", SCMP_CMP_GE},
        {"SCMP_CMP_GT", SCMP_CMP_GT},
        {"SCMP_CMP_MASKED_EQ", SCMP_CMP_MASKED_EQ}};
    for (const auto& [text, op] : kNames)
        if (name == text) return op;
    throw LaunchError("unsupported comparison " + name);
}

bool names_this_arch(const json& arches) {
    for (const auto& arch : arches)
        if (arch == "amd64" || arch == "x86_64" || arch == "SCMP_ARCH_X86_64") return true;
    return false;
}

// minKernel "4.8" against a release such as "6.18.44-fc": the major, then the minor number.
bool kernel_at_least(const std::string& minimum) {
    utsname host{};
    if (uname(&host) != 0) return false;
    unsigned want[2] = {0, 0}, have[2] = {0, 0};
    std::sscanf(minimum.c_str(), "%u.%u", &want[0], &want[1]);
    std::sscanf(host.release, "%u.%u", &have[0], &have[1]);
    return have[0] != want[0] ? have[0] > want[0] : have[1] >= want[1];
}

bool applies_here(const json& entry) {
    const json includes = entry.value("includes", json::object());
    const json excludes = entry.value("excludes", json::object());
    // The container holds no capability: what one grants never applies, what one takes away
    // always does.
    if (!includes.value("caps", json::array()).empty()) return false;
    if (includes.contains("arches") && !names_this_arch(includes["arches"])) return false;
    if (includes.contains("minKernel") && !kernel_at_least(includes["minKernel"])) return false;
    if (excludes.contains("arches") && names_this_arch(excludes["arches"])) return false;
    return true;
}

scmp_arg_cmp comparison_of(const json& arg) {
    return scmp_arg_cmp{
        arg.at("index").get<unsigned>(), comparison_named(arg.at("op").get<std::string>()),
        arg.at("value").get<scmp_datum_t>(), arg.value("valueTwo", scmp_datum_t{0})};
}

// One list of conditions per rule: all in one when each argument is compared once (AND), one
// rule per condition when an argument is compared twice (libseccomp refuses that in one rule).
std::vector<std::vector<scmp_arg_cmp>> rules_of(const json& args) {
    std::vector<scmp_arg_cmp> all;
    std::set<unsigned> indexes;
    for (const auto& arg : args) {
        all.push_back(comparison_of(arg));
        indexes.insert(all.back().arg);
    }
    if (indexes.size() == all.size()) return {all};
    std::vector<std::vector<scmp_arg_cmp>> each;
    for (const auto& one : all) each.push_back({one});
    return each;
}

std::vector<std::string> names_of(const json& entry) {
    auto names = entry.value("names", std::vector<std::string>{});
    if (entry.contains("name")) names.push_back(entry["name"].get<std::string>());
    return names;
}

void add_entry(const Filter& filter, std::uint32_t default_action, const json& entry) {
    if (!applies_here(entry)) return;
    std::uint32_t action =
        action_named(entry.at("action").get<std::string>(), entry.value("errnoRet", EPERM));
    // libseccomp refuses a rule that only repeats the default (runc skips it too).
    if (action == default_action) return;
    for (const auto& conditions : rules_of(entry.value("args", json::array())))
        for (const auto& name : names_of(entry)) add_rule(filter, action, name, conditions);
}

Filter profile_filter(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw LaunchError("cannot open " + path + ": " + std::strerror(errno));
    json profile;
    try {
        profile = json::parse(in);
    } catch (const json::exception& e) {
        throw LaunchError(path + ": " + e.what());
    }
    std::uint32_t default_action = action_named(profile.at("defaultAction").get<std::string>(),
                                                profile.value("defaultErrnoRet", EPERM));
    Filter filter = new_filter(default_action);
    for (const auto& entry : profile.value("syscalls", json::array()))
        add_entry(filter, default_action, entry);
    return filter;
}

int usage() {
    std::fprintf(stderr,
                 "usage: seccomp_run --deny-io-uring -- PROG [ARGS...]\n"
                 "       seccomp_run --profile FILE.json -- PROG [ARGS...]\n");
    return 2;
}
}  // namespace

int main(int argc, char** argv) {
    std::vector<std::string> options(argv + 1, argv + argc);
    bool deny = options.size() >= 3 && options[0] == "--deny-io-uring" && options[1] == "--";
    bool profile = options.size() >= 4 && options[0] == "--profile" && options[2] == "--";
    if (!deny && !profile) return usage();
    char** program = argv + (deny ? 3 : 4);
    try {
        Filter filter = deny ? deny_io_uring_filter() : profile_filter(options[1]);
        int rc = seccomp_load(filter.get());
        if (rc < 0) throw LaunchError(std::string("seccomp_load: ") + std::strerror(-rc));
    } catch (const std::exception& e) {
        std::fprintf(stderr, "seccomp_run: %s\n", e.what());
        return kLaunchFailed;
    }
    execvp(program[0], program);
    int failure = errno;
    std::fprintf(stderr, "seccomp_run: cannot execute %s: %s\n", program[0],
                 std::strerror(failure));
    return failure == ENOENT ? 127 : 126;
}
