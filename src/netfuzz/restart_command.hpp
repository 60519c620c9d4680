// The fuzzer's --restart-cmd as a child process (`sh -c CMD`) it does not block on: the command
// may return at once (`... &`), after a while (`systemctl restart plc`), or never, because it
// runs the target in the foreground. The fuzzer probes the target meanwhile either way.
#pragma once

#include <sys/types.h>

#include <string>

#include "util/error.hpp"

namespace mbstorm::netfuzz {

class RestartCommand {
  public:
    // Commands started from now on get a process group of their own, which stop() ends (the
    // target of --target-cmd, the fuzzer's to stop; a --restart-cmd stays in the user's).
    void own_process_group() noexcept { own_group_ = true; }
    // Ends a command still running and everything it started in its process group: SIGTERM,
    // then SIGKILL after a second.
    void stop();
    // Starts the command; an Io error when it cannot be started at all.
    Error start(const std::string& command);
    // True once the command has returned (it is reaped then).
    bool returned();
    // Started and not yet returned: starting another copy now would race it.
    bool running() { return pid_ >= 0 && !returned(); }
    // A command still running is left running: it may be the target itself. Commands left
    // running earlier are reaped here once they end, so none stays a zombie.
    ~RestartCommand();

  private:
    Error start_owned(const std::string& command);
    pid_t pid_ = -1;
    bool own_group_ = false;
};

}  // namespace mbstorm::netfuzz
