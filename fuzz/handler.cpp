// libFuzzer harness: arbitrary bytes as a request PDU into the slave handler on a small model.
// The response must stay within one PDU, decode with codec::decode_response, and answer the
// request's own function code (normally or as its exception).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>

#include "codec/pdu.hpp"
#include "slave/data_model.hpp"
#include "slave/handler.hpp"

namespace {

using namespace mbstorm;

slave::UnitModels make_units() {
    slave::ModelConfig c;
    c.sizes = {64, 48, 32, 80};  // small: most addresses are out of range
    c.file_count = 2;
    c.file_records = 100;
    c.identity.set(0x80, std::string(200, 'x'));  // forces more-follows on extended streams
    c.identity.set(0x81, "y");
    const std::uint8_t ids[] = {1, 2};
    slave::UnitModels units = slave::UnitModels::per_unit(c, ids);
    units.find(1)->holding_registers().set(40, 3);  // a FIFO at 40
    units.find(1)->holding_registers().add_read_counter(5, 1);
    return units;
}

void check(bool ok) {
    if (!ok) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static slave::UnitModels units = make_units();
    if (size == 0) return 0;
    // First byte picks the unit (1, 2, unknown 3); the rest is the PDU.
    const std::uint8_t unit = static_cast<std::uint8_t>(1 + data[0] % 3);
    const codec::Bytes pdu(data + 1, size - 1);
    std::uint8_t out[slave::kMinOutput + 16];
    std::memset(out, 0xEE, sizeof out);
    const slave::HandleResult r =
        slave::handle_request(unit, pdu, units, codec::MutableBytes(out, slave::kMinOutput));

    check(out[slave::kMinOutput] == 0xEE);  // never writes past the buffer it was given
    if (pdu.empty()) {
        check(r.outcome == slave::Outcome::NoResponse);
        return 0;
    }
    check(r.outcome != slave::Outcome::NoResponse);
    check(r.size >= 2 && r.size <= 253);
    const std::uint8_t fc = pdu[0];
    if (r.outcome == slave::Outcome::Exception) {
        check(r.size == 2);
        check(out[0] == (fc | 0x80));
        check(out[1] == static_cast<std::uint8_t>(r.exception));
        check(codec::is_known_exception(out[1]));
    } else {
        check(out[0] == fc);
        check((fc & 0x80) == 0);
    }
    if (fc == 0 || (fc & 0x80) != 0) return 0;  // no function code to decode against
    codec::Response rsp;
    check(codec::decode_response(codec::Bytes(out, r.size), rsp) == codec::CodecError::Ok);
    check(rsp.function == fc);
    check((rsp.exception != codec::ExceptionCode::None) ==
          (r.outcome == slave::Outcome::Exception));
    return 0;
}
