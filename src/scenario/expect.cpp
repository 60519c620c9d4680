#include "scenario/expect.hpp"

#include "codec/bytes.hpp"
#include "codec/values.hpp"

namespace mbstorm::scenario {
namespace {

bool item_matches(const Expectation& e, std::uint16_t address, std::uint16_t item) noexcept {
    if (e.value && item != *e.value) return false;
    if (e.min && item < *e.min) return false;
    if (e.max && item > *e.max) return false;
    if (!e.values.empty()) {
        const std::uint32_t index = static_cast<std::uint32_t>(address) - e.first_address;
        // Addresses outside the list are not checked (validation makes the list cover them).
        if (address >= e.first_address && index < e.values.size() && item != e.values[index]) {
            return false;
        }
    }
    return true;
}

bool verify(void* context, const load::RequestInfo& request, const codec::Response& response) {
    const auto& expectations = *static_cast<const std::vector<Expectation>*>(context);
    if (request.op_index >= expectations.size()) return true;
    return response_matches(expectations[request.op_index], request, response);
}

}  // namespace

bool can_expect(std::uint8_t function) noexcept {
    switch (function) {
        case 0x01:
        case 0x02:
        case 0x03:
        case 0x04:
        case 0x17:
            return true;
        default:
            return false;
    }
}

bool response_matches(const Expectation& e, const load::RequestInfo& request,
                      const codec::Response& response) noexcept {
    if (!e.active) return true;
    const codec::Bytes data = response.payload;
    switch (request.function) {
        case 0x01:
        case 0x02: {
            if (data.size() < codec::packed_bit_bytes(request.quantity)) return false;
            for (std::uint16_t i = 0; i < request.quantity; ++i) {
                const std::uint16_t bit = codec::bit_at(data, i) ? 1 : 0;
                if (!item_matches(e, static_cast<std::uint16_t>(request.address + i), bit)) {
                    return false;
                }
            }
            return true;
        }
        case 0x03:
        case 0x04:
        case 0x17: {
            if (data.size() < 2U * request.quantity) return false;
            for (std::uint16_t i = 0; i < request.quantity; ++i) {
                const std::uint16_t reg = codec::load_be16(data.data() + 2U * i);
                if (!item_matches(e, static_cast<std::uint16_t>(request.address + i), reg)) {
                    return false;
                }
            }
            return true;
        }
        default:
            return true;
    }
}

load::ResponseVerifier make_verifier(const std::vector<Expectation>& expectations) noexcept {
    load::ResponseVerifier v;
    bool any = false;
    for (const auto& e : expectations) any = any || e.active;
    if (!any) return v;
    v.check = &verify;
    v.context = const_cast<std::vector<Expectation>*>(&expectations);
    return v;
}

}  // namespace mbstorm::scenario
