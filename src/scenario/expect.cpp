#include "scenario/expect.hpp"

#include "codec/bytes.hpp"
#include "codec/function_code.hpp"
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
    return codec::response_is(function, codec::ResponseShape::Bits) ||
           codec::response_is(function, codec::ResponseShape::Registers);
}

bool response_matches(const Expectation& e, const load::RequestInfo& request,
                      const codec::Response& response) noexcept {
    if (!e.active) return true;
    const codec::Bytes data = response.payload;
    if (codec::response_is(request.function, codec::ResponseShape::Bits)) {
        if (data.size() < codec::packed_bit_bytes(request.quantity)) return false;
        for (std::uint16_t i = 0; i < request.quantity; ++i) {
            const std::uint16_t bit = codec::bit_at(data, i) ? 1 : 0;
            if (!item_matches(e, static_cast<std::uint16_t>(request.address + i), bit)) {
                return false;
            }
        }
        return true;
    }
    if (codec::response_is(request.function, codec::ResponseShape::Registers)) {
        if (data.size() < 2U * request.quantity) return false;
        for (std::uint16_t i = 0; i < request.quantity; ++i) {
            const std::uint16_t reg = codec::load_be16(data.data() + 2U * i);
            if (!item_matches(e, static_cast<std::uint16_t>(request.address + i), reg)) {
                return false;
            }
        }
        return true;
    }
    return true;
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
