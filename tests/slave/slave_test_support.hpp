// Helpers for the slave tests: build request PDUs byte by byte, run the handler, decode.
#pragma once

#include <cstdint>
#include <initializer_list>
#include <vector>

#include "codec/pdu.hpp"
#include "slave/data_model.hpp"
#include "slave/handler.hpp"

namespace mbstorm::slave::test {

// Request bytes built field by field, so malformed PDUs are as easy to write as good ones.
class Pdu {
  public:
    explicit Pdu(std::uint8_t function) { bytes_.push_back(function); }
    Pdu& u8(unsigned v) {
        bytes_.push_back(static_cast<std::uint8_t>(v));
        return *this;
    }
    Pdu& u16(unsigned v) {
        bytes_.push_back(static_cast<std::uint8_t>(v >> 8));
        bytes_.push_back(static_cast<std::uint8_t>(v));
        return *this;
    }
    Pdu& words(std::initializer_list<unsigned> vs) {
        for (unsigned v : vs) u16(v);
        return *this;
    }
    const std::vector<std::uint8_t>& bytes() const { return bytes_; }
    operator const std::vector<std::uint8_t>&() const { return bytes_; }

  private:
    std::vector<std::uint8_t> bytes_;
};

struct Reply {
    HandleResult result;
    std::vector<std::uint8_t> bytes;
    codec::Response decoded;
    codec::CodecError decode_error = codec::CodecError::Ok;

    bool is_exception(codec::ExceptionCode code) const {
        return result.outcome == Outcome::Exception && result.exception == code &&
               bytes.size() == 2 && bytes[1] == static_cast<std::uint8_t>(code);
    }
    // Register i of a FC03/04/17 response.
    std::uint16_t reg(std::size_t i) const { return codec::load_be16(bytes.data() + 2 + 2 * i); }
};

inline Reply finish(const HandleResult& r, const std::uint8_t* out) {
    Reply reply;
    reply.result = r;
    reply.bytes.assign(out, out + r.size);
    if (r.size > 0) reply.decode_error = codec::decode_response(reply.bytes, reply.decoded);
    return reply;
}

inline Reply call(DataModel& model, const std::vector<std::uint8_t>& request) {
    std::uint8_t out[kMinOutput];
    return finish(handle_request(request, model, out), out);
}

inline Reply call(const UnitModels& units, std::uint8_t unit,
                  const std::vector<std::uint8_t>& request) {
    std::uint8_t out[kMinOutput];
    return finish(handle_request(unit, request, units, out), out);
}

inline ModelConfig small_config(std::uint32_t size = 100) {
    ModelConfig c;
    c.sizes = {size, size, size, size};
    return c;
}

}  // namespace mbstorm::slave::test
