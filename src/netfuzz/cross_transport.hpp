// The other transport spoken to the port: plain Modbus/TCP to a Modbus/TCP Security (TLS)
// port, on a fresh TCP connection or between the records of an established session, and TLS
// (a ClientHello, alone, split, or followed by more records) to a plain Modbus/TCP port.
// A conforming server refuses or closes that one connection (a TLS alert is fine) and goes on
// serving the others. Findings: it answers the foreign bytes as Modbus (a TLS port that serves
// plaintext defeats the security), it stalls other connections while it holds the foreign one,
// or it crashes or hangs as a whole. The campaign runs these cases once, after discovery; replay
// runs them from their saved bytes like any other case.
#pragma once

#include <vector>

#include "netfuzz/case.hpp"
#include "netfuzz/executor.hpp"
#include "netfuzz/link.hpp"
#include "netfuzz/oracle.hpp"

namespace mbstorm::netfuzz {

bool is_cross_transport(MutationClass c) noexcept;

// The cases for this target's transport: plaintext ones for a TLS target, TLS ones for a plain
// Modbus/TCP target, none for others.
std::vector<Case> cross_transport_cases(const Connector& target, const TargetProfile& profile);

// Runs one such case (execute_case hands them here) and judges it.
Execution execute_cross_transport(const Case& c, Connector& target, const TargetProfile& profile,
                                  const ExecOptions& options);

}  // namespace mbstorm::netfuzz
