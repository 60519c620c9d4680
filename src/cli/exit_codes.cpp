// How the CLI stops on an Error: its exit code and its line on stderr, in one place.
#include <fmt/format.h>

#include "cli/commands.hpp"

namespace mbstorm::cli {

int exit_code_for(const Error& error) {
    switch (error.code()) {
        case ErrorCode::Ok:
            return kExitOk;
        case ErrorCode::InvalidInput:
        case ErrorCode::NotFound:
        case ErrorCode::Io:
        case ErrorCode::Network:
        case ErrorCode::Unsupported:
        case ErrorCode::Refused:
        case ErrorCode::Interrupted:
            // The user's to act on: a flag, a file, the target, this machine (README: "Usage
            // errors ... exit with code 2"; the Kubernetes verdict: 2 an error).
            return kExitUsage;
    }
    return kExitUsage;
}

int fail(std::string_view command, const Error& error) {
    const std::string text = error.text();
    std::string_view rest = text;
    // One "mbstorm <command>: " per line, so an error listing several problems reads as before.
    for (;;) {
        const std::size_t end = rest.find('\n');
        fmt::print(stderr, "mbstorm {}: {}\n", command, rest.substr(0, end));
        if (end == std::string_view::npos) break;
        rest.remove_prefix(end + 1);
    }
    return exit_code_for(error);
}

int usage_error(std::string_view command, std::string_view message) {
    return fail(command, Error(ErrorCode::InvalidInput, std::string(message)));
}

}  // namespace mbstorm::cli
