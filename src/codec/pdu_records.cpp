// Iterators over the variable parts of FC14/15 and FC2B/0E PDUs, and the FC14/15 checks.
#include <algorithm>
#include <cstddef>

#include "codec/pdu.hpp"
#include "codec/pdu_rules.hpp"

namespace mbstorm::codec {

CodecError FileRecordIterator::next(FileSubRequest& out) noexcept {
    if (rest_.empty()) return CodecError::Empty;
    constexpr std::size_t kHeader = 7;  // reference type, file, record, length
    if (rest_.size() < kHeader) return CodecError::Truncated;
    const std::uint8_t* p = rest_.data();
    out.reference_type = p[0];
    out.file_number = load_be16(p + 1);
    out.record_number = load_be16(p + 3);
    out.record_length = load_be16(p + 5);
    std::size_t data_size = with_data_ ? std::size_t{out.record_length} * 2u : 0u;
    if (rest_.size() - kHeader < data_size) return CodecError::Truncated;
    out.record_data = rest_.subspan(kHeader, data_size);
    rest_ = rest_.subspan(kHeader + data_size);
    return CodecError::Ok;
}

EncodeResult encode_file_sub_request(const FileSubRequest& sub, MutableBytes out) noexcept {
    constexpr std::size_t kHeader = 7;  // reference type, file, record, length
    const std::size_t size = kHeader + sub.record_data.size();
    if (out.size() < size) return {0, CodecError::BufferTooSmall};
    std::uint8_t* p = out.data();
    p[0] = sub.reference_type;
    store_be16(p + 1, sub.file_number);
    store_be16(p + 3, sub.record_number);
    store_be16(p + 5, sub.record_length);
    std::copy(sub.record_data.begin(), sub.record_data.end(), p + kHeader);
    return {size, CodecError::Ok};
}

CodecError FileResponseIterator::next(FileSubResponse& out) noexcept {
    if (rest_.empty()) return CodecError::Empty;
    const std::size_t length = rest_[0];  // counts the reference type and the data
    if (length == 0) return CodecError::ByteCountMismatch;
    if (rest_.size() - 1u < length) return CodecError::Truncated;
    out.reference_type = rest_[1];
    out.record_data = rest_.subspan(2, length - 1u);
    rest_ = rest_.subspan(1u + length);
    return CodecError::Ok;
}

CodecError DeviceIdObjectIterator::next(DeviceIdObject& out) noexcept {
    if (rest_.empty()) return CodecError::Empty;
    if (rest_.size() < 2) return CodecError::Truncated;
    const std::size_t length = rest_[1];
    if (rest_.size() - 2u < length) return CodecError::Truncated;
    out.id = rest_[0];
    out.value = rest_.subspan(2, length);
    rest_ = rest_.subspan(2u + length);
    return CodecError::Ok;
}

namespace detail {

FileCheck check_file_sub_requests(Bytes sub_requests, bool with_data) noexcept {
    constexpr FileCheck kBadValue{CodecError::QuantityOutOfRange, ExceptionCode::IllegalDataValue};
    // Pass 1: shape and sizes (exception 03).
    std::size_t response_bytes = 0;  // FC14: the sub-responses this request asks for
    FileRecordIterator shape(sub_requests, with_data);
    FileSubRequest sub;
    CodecError e;
    while ((e = shape.next(sub)) == CodecError::Ok) {
        if (sub.record_length == 0) return kBadValue;
        response_bytes += 2u + 2u * std::size_t{sub.record_length};
    }
    if (e != CodecError::Empty) {
        // The byte count covered the bytes, but they do not split into whole sub-requests.
        return {CodecError::ByteCountMismatch, ExceptionCode::IllegalDataValue};
    }
    if (!with_data && response_bytes > limits::kMaxFileResponseBytes) return kBadValue;

    // Pass 2: reference type, file number and record range (exception 02).
    FileRecordIterator where(sub_requests, with_data);
    while (where.next(sub) == CodecError::Ok) {
        if (sub.reference_type != limits::kFileReferenceType) {
            return {CodecError::InvalidReferenceType, ExceptionCode::IllegalDataAddress};
        }
        const bool records_fit = std::uint32_t{sub.record_number} + sub.record_length <=
                                 std::uint32_t{limits::kMaxFileRecordNumber} + 1u;
        if (sub.file_number < limits::kMinFileNumber || !records_fit) {
            return {CodecError::AddressOverflow, ExceptionCode::IllegalDataAddress};
        }
    }
    return {};
}

}  // namespace detail
}  // namespace mbstorm::codec
