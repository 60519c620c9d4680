#include <fmt/format.h>

#include <cstdio>

#include "cli/commands.hpp"
#include "cli/version.hpp"

namespace mbstorm::cli {

int run_cli(int argc, char** argv) {
    CLI::App app{"mbstorm: Modbus TCP load tester, reference slave and fuzzer", "mbstorm"};
    app.require_subcommand(1);
    // Probed only when asked: the io_uring probe opens rings and sockets.
    app.set_version_flag("--version", [] { return version_text(build_info(), net::features()); });
    Action action;
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
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        // One clear line, exit code 2, as for every usage error.
        fmt::print(stderr, "mbstorm: {}\n", e.what());
        return kExitUsage;
    }
    return action ? action() : kExitUsage;
}

}  // namespace mbstorm::cli
