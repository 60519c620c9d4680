#include "cli/help_footers.hpp"

#include <fmt/format.h>

#include <string_view>

namespace mbstorm::cli {
namespace {

struct Footer {
    std::string_view command;
    std::string_view examples;     // one command per line, with what it does
    std::string_view exit_status;  // what each code means for this command
};

// 128 + the signal, as shells report it: run and fuzz write their reports first.
constexpr std::string_view kInterrupted =
    "\n  130, 143  interrupted by SIGINT, SIGTERM (reports are still written)";

constexpr Footer kFooters[] = {
    {"run",
     "  mbstorm run                                   embedded slave, 16 x 16, 10 s\n"
     "  mbstorm run --target 192.0.2.10:502 -c 64 --depth 4 -d 30s --addr 40001-40100\n"
     "  mbstorm run --target 127.0.0.1:5020 --rate 5000 -d 1m --threshold 'p99 < 5ms' "
     "--junit ci.xml\n"
     "  mbstorm run quickstart                        a packaged scenario, by name\n"
     "  mbstorm run ci-gate.yaml --target 127.0.0.1:5020 --json out.json --html out.html",
     "  0  the run completed (every threshold passed)\n"
     "  1  a threshold was breached, no transaction succeeded, or the target was lost\n"
     "  2  bad flags or scenario, an unreachable target, a report path that cannot be written"},
    {"serve",
     "  mbstorm serve                                 127.0.0.1:5020 until Ctrl-C\n"
     "  mbstorm serve --listen 0.0.0.0:502 --device plc.yaml --threads 2\n"
     "  mbstorm serve --exception-rate 1% --delay 5ms -d 10m   fault injection",
     "  0  served until stopped (SIGINT, SIGTERM or --duration)\n"
     "  2  bad flags or device file, or the address cannot be listened on"},
    {"decode",
     "  mbstorm decode 01 03 00 00 00 0A C5 CD          an RTU frame\n"
     "  mbstorm decode --tcp 00 01 00 00 00 06 01 03 00 6B 00 03",
     "  0  the bytes are a sound frame\n"
     "  1  a frame with a fault (shown with the faulty field marked)\n"
     "  2  bytes that fit no framing, or bad input"},
    {"encode",
     "  mbstorm encode --fc 3 --addr 40001 --quantity 10 --unit 1\n"
     "  mbstorm encode --fc write_multiple_registers --addr 100 --values 1 2 3 --rtu",
     "  0  the frame was printed\n"
     "  2  bad fields"},
    {"fuzz",
     "  mbstorm fuzz --target 127.0.0.1:5020 --seconds 60\n"
     "  mbstorm fuzz --target 127.0.0.1:5020 -d 5m --restart-cmd './plc --port 5020 &' "
     "--sarif fuzz.sarif\n"
     "  mbstorm fuzz --target 127.0.0.1:5020 -d 5m --wait-for-target 30s --baseline known.json\n"
     "  mbstorm fuzz --coverage --target-cmd 'exec ./plc --port 5020' --target 127.0.0.1:5020 "
     "-d 2m",
     "  0  no finding (with --baseline: no finding it does not list)\n"
     "  1  findings, or the target was lost and not back\n"
     "  2  bad flags, or a target that cannot be reached or started on"},
    {"replay",
     "  mbstorm replay mbstorm-findings/001-crash-target-down-fc0F --target 127.0.0.1:5020\n"
     "  mbstorm replay finding.json --target 127.0.0.1:5020 --runs 5",
     "  0  the finding did not reproduce\n"
     "  1  it reproduced (k of n runs said)\n"
     "  2  bad flags, an unreadable finding, or an unreachable target"},
    {"read",
     "  mbstorm read --target 192.0.2.10 --addr 40001-40010          ten holding registers\n"
     "  mbstorm read --target 192.0.2.10 -u 3 --addr 30001 --quantity 2 --type f32\n"
     "  mbstorm read --target 192.0.2.10 --addr 00001-00016 -n 0 --interval 500ms   poll",
     "  0  every transaction was answered normally\n"
     "  1  an exception (named on stderr), a timeout or a malformed answer\n"
     "  2  bad flags or an unreachable target"},
    {"write",
     "  mbstorm write --target 127.0.0.1:5020 --addr 40001 1234\n"
     "  mbstorm write --target 192.0.2.10 --allow-writes --addr 40101 --type f32 3.5 -1.25\n"
     "  mbstorm write --target 127.0.0.1:5020 --addr 00001 on off on",
     "  0  every write was acknowledged\n"
     "  1  an exception (named on stderr), a timeout or a malformed answer\n"
     "  2  bad flags, a write outside loopback without --allow-writes, an unreachable target"},
    {"merge",
     "  mbstorm merge shard-*.json shard-*.hlog --expect 4 --json all.json --html all.html\n"
     "  mbstorm merge a.json a.hlog b.json b.hlog --scenario ci-gate.yaml --junit all.xml",
     "  0  merged, every threshold passed\n"
     "  1  a threshold was breached on the merged result\n"
     "  2  bad or missing shard files, shards of different tests, times or counts no run\n"
     "     writes (offsets outside a run, a span of over 1,000,000 intervals), bad flags"},
};

}  // namespace

void add_help_footers(CLI::App& app, const std::string& scenarios_dir) {
    for (const Footer& f : kFooters) {
        CLI::App* sub = nullptr;
        for (CLI::App* s : app.get_subcommands({}))
            if (s->get_name() == f.command) sub = s;
        if (!sub) continue;
        const bool signals = f.command == "run" || f.command == "fuzz";
        std::string text = fmt::format("\nExamples:\n{}\n\nExit status:\n{}{}\n", f.examples,
                                       f.exit_status, signals ? kInterrupted : "");
        if (f.command == "run" && !scenarios_dir.empty())
            text += fmt::format(
                "\nFiles:\n  {}  the packaged scenarios (run NAME finds "
                "NAME.yaml there)\n",
                scenarios_dir);
        sub->footer(text);
    }
}

}  // namespace mbstorm::cli
