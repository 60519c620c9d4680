#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cctype>
#include <cstdio>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "cli/commands.hpp"
#include "cli/help_footers.hpp"
#include "cli/packaged_files.hpp"
#include "cli/version.hpp"
#include "util/closest_name.hpp"

namespace mbstorm::cli {
namespace {

// The subcommand named `name`, or nullptr: CLI11's get_subcommand throws instead.
const CLI::App* find_subcommand(const CLI::App& app, std::string_view name) {
    auto found = app.get_subcommands(
        [name](const CLI::App* sub) { return sub->check_name(std::string(name)); });
    return found.empty() ? nullptr : found.front();
}

// The one of `names` that `typed` is a near miss of, or "". Options compare without their
// dashes: "--conections" is one edit from "--connections" in a word of ten letters, not twelve.
std::string near_miss(std::string_view typed, const std::vector<std::string>& names) {
    auto bare = [](std::string_view name) {
        const std::size_t letters = name.find_first_not_of('-');
        return letters == std::string_view::npos ? std::string_view() : name.substr(letters);
    };
    std::vector<std::string_view> bare_names;
    for (const std::string& name : names) bare_names.push_back(bare(name));
    const std::string_view closest = util::closest_name(bare(typed), bare_names);
    if (closest.empty()) return {};
    // closest_name returns one of bare_names: the same position in `names`.
    for (std::size_t i = 0; i < names.size(); ++i)
        if (bare_names[i].data() == closest.data()) return names[i];
    return {};
}

// Every spelling of the options --help shows for `command`: deprecated spellings still work
// but are never suggested.
std::vector<std::string> visible_option_names(const CLI::App& command) {
    std::vector<std::string> names;
    for (const CLI::Option* opt : command.get_options()) {
        if (!opt->nonpositional() || opt->get_group().empty()) continue;
        for (const std::string& s : opt->get_snames()) names.push_back("-" + s);
        for (const std::string& l : opt->get_lnames()) names.push_back("--" + l);
    }
    return names;
}

// The same permission under two names, as it allows different things: writes (run, write) or
// any traffic at all (fuzz, replay) to a target outside loopback. Each is the other's near miss.
constexpr std::pair<std::string_view, std::string_view> kCounterparts[] = {
    {"--allow-writes", "--allow-remote"},
    {"--allow-remote", "--allow-writes"},
};

// The near miss of the unknown option `name` among `command`'s options, or "".
std::string option_near_miss(const CLI::App& command, const std::string& name) {
    for (const auto& [typed, counterpart] : kCounterparts)
        if (name == typed && command.get_option_no_throw(std::string(counterpart)) != nullptr)
            return std::string(counterpart);
    return near_miss(name, visible_option_names(command));
}

// The option that `word` names ("--depth", "--depth=4", "-c", "-c4"), or "" when `word` is a
// value (a plain word, a negative number, "-").
std::string option_name_in(std::string_view word) {
    if (word.size() > 2 && word.starts_with("--"))
        return std::string(word.substr(0, word.find('=')));
    if (word.size() >= 2 && word[0] == '-' && std::isalpha(static_cast<unsigned char>(word[1])))
        return std::string(word.substr(0, 2));
    return {};
}

// An unknown option of `command` in `args`, with the near miss it may be a typo of; "" when
// every option is known. Checked before CLI11 parses: it would take the word after an unknown
// option as a positional argument and complain about that instead.
std::string unknown_option(const CLI::App& command, const std::vector<std::string>& args) {
    for (const std::string& word : args) {
        if (word == "--") break;  // what follows is values only
        const std::string name = option_name_in(word);
        if (name.empty() || command.get_option_no_throw(name) != nullptr) continue;
        const std::string hint = option_near_miss(command, name);
        return hint.empty() ? fmt::format("unknown option {} (see mbstorm {} --help)", name,
                                          command.get_name())
                            : fmt::format("unknown option {}; did you mean {}?", name, hint);
    }
    return {};
}

std::vector<std::string> visible_subcommand_names(const CLI::App& app) {
    std::vector<std::string> names;
    for (const CLI::App* sub : app.get_subcommands({}))
        if (!sub->get_group().empty()) names.push_back(sub->get_name());
    return names;
}

// Refuses, before CLI11 parses, what it would misreport: no subcommand at all (the usage and
// the list of subcommands, not only "A subcommand is required"), an unknown subcommand and an
// unknown option (each with its near miss). Returns -1 to go on and parse; sets `command` to
// the subcommand named, so that CLI11's own errors can name it too.
int refuse_unknown_names(const CLI::App& app, const std::vector<std::string>& args,
                         std::string& command) {
    if (args.empty()) {
        fmt::print(stderr,
                   "{}\nmbstorm: which subcommand? (mbstorm SUBCOMMAND --help tells more)\n",
                   app.help());
        return kExitUsage;
    }
    if (args.front().starts_with("-")) return -1;  // --help, --version: CLI11's
    const CLI::App* sub = find_subcommand(app, args.front());
    if (sub == nullptr) {
        const std::vector<std::string> names = visible_subcommand_names(app);
        const std::string hint = near_miss(args.front(), names);
        fmt::print(stderr, "mbstorm: unknown subcommand '{}'; {}\n", args.front(),
                   hint.empty() ? fmt::format("the subcommands are {}", fmt::join(names, ", "))
                                : fmt::format("did you mean '{}'?", hint));
        return kExitUsage;
    }
    command = sub->get_name();
    if (std::string e = unknown_option(*sub, {args.begin() + 1, args.end()}); !e.empty())
        return usage_error(command, e);
    return -1;
}

}  // namespace

void add_all_commands(CLI::App& app, Action& action) {
    add_run_command(app, action);
    add_serve_command(app, action);
    add_decode_command(app, action);
    add_encode_command(app, action);
    add_fuzz_command(app, action);
    add_replay_command(app, action);
    add_read_command(app, action);
    add_write_command(app, action);
    add_merge_command(app, action);
    add_completion_command(app, action);
    add_help_footers(app, packaged_dir("scenarios"));
}

int run_cli(int argc, char** argv) {
    CLI::App app{"mbstorm: Modbus TCP load tester, reference slave and fuzzer", "mbstorm"};
    app.require_subcommand(1);
    // Probed only when asked: the io_uring probe opens rings and sockets.
    app.set_version_flag("--version", [] {
        // What `--backend auto` picks (run needs provided-buffer rings, serve does not).
        // Auto never fails: it falls back to epoll.
        const net::BackendDecision run = *net::choose_backend(net::BackendChoice::Auto, true);
        const net::BackendDecision serve = *net::choose_backend(net::BackendChoice::Auto, false);
        return version_text(build_info(), net::features(), run, serve);
    });
    Action action;
    add_all_commands(app, action);
    std::string command;
    if (int refused = refuse_unknown_names(app, {argv + 1, argv + argc}, command); refused >= 0)
        return refused;
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        // One clear line naming the subcommand, exit code 2, as for every usage error.
        if (!command.empty()) return usage_error(command, e.what());
        fmt::print(stderr, "mbstorm: {}\n", e.what());
        return kExitUsage;
    }
    return action ? action() : kExitUsage;
}

}  // namespace mbstorm::cli
