// RTU over TCP for the load engine: requests are encoded as MBAP by the generator and rewritten
// as RTU frames; answers carry no transaction id, so with one request outstanding per
// connection (the plan's depth is 1) each answer belongs to the last request sent.
#include "load/worker.hpp"

namespace mbstorm::load {

std::size_t Worker::rtu_request(Connection& c, std::uint8_t* at, std::size_t size,
                                const Transaction& t) noexcept {
    c.rtu_transaction = t.transaction_id();
    return codec::mbap_to_rtu_in_place(at, size);
}

codec::CodecError Worker::consume_rtu(Connection& c, const std::uint8_t* data, std::size_t size,
                                      std::int64_t now) noexcept {
    c.rtu->feed(codec::Bytes(data, size));
    codec::TcpFrame frame;
    for (;;) {
        switch (c.rtu->next(frame)) {
            case codec::RtuSplitter::Status::Frame:
                frame.header.transaction_id = c.rtu_transaction;
                on_frame(c, frame, now);
                break;
            case codec::RtuSplitter::Status::NeedMore:
                return codec::CodecError::Ok;
            case codec::RtuSplitter::Status::Skipped:  // not asked for here: an answer with a
                return codec::CodecError::BadCrc;      // bad CRC is an error of the target's
            case codec::RtuSplitter::Status::Fatal:
                return c.rtu->error();
        }
    }
}

}  // namespace mbstorm::load
