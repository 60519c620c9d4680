#include "netfuzz/case_json.hpp"

#include "netfuzz/finding.hpp"

namespace mbstorm::netfuzz {

nlohmann::json steps_to_json(const Case& c) {
    nlohmann::json steps = nlohmann::json::array();
    for (const Step& s : c.steps)
        steps.push_back({{"op", op_name(s.op)},
                         {"conn", s.conn},
                         {"delay_us", s.delay_us},
                         {"count", s.count},
                         {"hex", to_hex(s.bytes)}});
    return steps;
}

void steps_from_json(const nlohmann::json& steps, Case& c, std::size_t max_steps) {
    if (!steps.is_array()) throw std::runtime_error("'steps' is not a list");
    for (const nlohmann::json& s : steps) {
        Step st;
        if (!op_from_name(s.at("op").get<std::string>(), st.op))
            throw std::runtime_error("unknown step op");
        st.conn = static_cast<std::uint8_t>(whole_number(s, "conn", 0, 0, 7));
        st.delay_us = static_cast<std::uint32_t>(whole_number(s, "delay_us", 0, 0, 60'000'000));
        st.count = static_cast<std::uint16_t>(whole_number(s, "count", 0, 0, 0xFFFF));
        if (!from_hex(s.value("hex", ""), st.bytes)) throw std::runtime_error("bad hex");
        c.steps.push_back(std::move(st));
        if (c.steps.size() > max_steps) throw std::runtime_error("case too large");
    }
}

}  // namespace mbstorm::netfuzz
