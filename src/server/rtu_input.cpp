// RTU over TCP input: RTU frames (address, PDU, CRC) cut from the stream by the codec's length
// inference, then served like MBAP frames (Worker::serve_frame writes the RTU answer). No
// transaction ids: answers go out in request order, as they always do here. A frame with a bad
// CRC is dropped and the next one served, as a serial slave behind a gateway does, so the
// gateway keeps its link; only a bad frame with no length rule to find its end closes it.
#include "server/worker.hpp"

namespace mbstorm::server {

void Worker::consume_rtu_input(std::uint32_t index, const std::uint8_t* data,
                               std::size_t size) noexcept {
    Connection& c = conns_[index];
    c.rtu->feed(codec::Bytes(data, size));
    codec::TcpFrame frame;
    bool completed = false;
    for (;;) {
        switch (c.rtu->next(frame)) {
            case codec::RtuSplitter::Status::NeedMore:
                counters_.set_max(ServerCounters::PendingOutputPeak, c.out.bytes());
                note_partial_frame(c, index, completed);
                return;
            case codec::RtuSplitter::Status::Skipped:
                counters_.add(ServerCounters::CrcErrors);
                break;
            case codec::RtuSplitter::Status::Fatal:
                // No length rule to resynchronise on: the frames before it are answered and
                // the connection closes after that.
                lose_framing(index, c.rtu->error() == codec::CodecError::BadCrc);
                return;
            case codec::RtuSplitter::Status::Frame:
                if (!serve_frame(c, index, frame)) return;
                completed = true;
                break;
        }
    }
}

}  // namespace mbstorm::server
