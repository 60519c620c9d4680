// The fuzzer's --restart-cmd as a child process (`sh -c CMD`) it does not block on: the command
// may return at once (`... &`), after a while (`systemctl restart plc`), or never, because it
// runs the target in the foreground. The fuzzer probes the target meanwhile either way.
#pragma once

#include <sys/types.h>

#include <string>

namespace mbstorm::netfuzz {

class RestartCommand {
  public:
    // Starts the command; false with `error` when it cannot be started at all.
    bool start(const std::string& command, std::string& error);
    // True once the command has returned (it is reaped then).
    bool returned();
    // Started and not yet returned: starting another copy now would race it.
    bool running() { return pid_ >= 0 && !returned(); }
    // A command still running is left running: it may be the target itself. Commands left
    // running earlier are reaped here once they end, so none stays a zombie.
    ~RestartCommand();

  private:
    pid_t pid_ = -1;
};

}  // namespace mbstorm::netfuzz
