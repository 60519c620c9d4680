// Planted fault: closes the connection on a request it cannot decode (too short or too long for
// its function code) instead of answering it with an exception, as pymodbus 3.0 does. It frames
// by the MBAP length, so the stream is never lost: a close after a request of the wrong length
// is this one refusal, the same root cause as a close after any other undecodable request.
#include "broken_server_common.hpp"
#include "codec/pdu.hpp"

namespace {
broken::Action refuse_undecodable(const std::uint8_t* adu, std::size_t size,
                                  std::vector<std::uint8_t>&, mbstorm::slave::DataModel&) {
    namespace codec = mbstorm::codec;
    if (size <= codec::limits::kMbapHeader) return broken::Action::Default;
    codec::Request request;
    const codec::RequestStatus status = codec::decode_request(
        codec::Bytes(adu + codec::limits::kMbapHeader, size - codec::limits::kMbapHeader), request);
    const bool undecodable = status.error == codec::CodecError::Truncated ||
                             status.error == codec::CodecError::TrailingBytes ||
                             status.error == codec::CodecError::ByteCountMismatch;
    return undecodable ? broken::Action::Close : broken::Action::Default;
}
}  // namespace

int main(int argc, char** argv) {
    broken::Faults f;
    f.on_frame = refuse_undecodable;
    return broken::main_with(argc, argv, f);
}
