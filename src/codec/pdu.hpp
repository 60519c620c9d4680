// Request and response PDUs of every public function code: decode into views over the
// caller's bytes, encode into the caller's buffer. No heap, no exceptions.
#pragma once

#include <cstddef>
#include <cstdint>

#include "codec/bytes.hpp"
#include "codec/error.hpp"
#include "codec/exception_code.hpp"
#include "codec/function_code.hpp"

namespace mbstorm::codec {

// One request PDU. Which fields mean something depends on `function`; the rest stay 0.
// `payload` points into the bytes that were decoded (or that the encoder should copy).
struct Request {
    std::uint8_t function = 0;
    std::uint16_t address =
        0;  // FC01-06,0F,10,16: start/target; FC17: read start; FC18: FIFO pointer
    std::uint16_t quantity = 0;        // FC01-04,0F,10: count; FC17: read count
    std::uint16_t value = 0;           // FC05: 0xFF00/0x0000; FC06: register value
    std::uint16_t and_mask = 0;        // FC16
    std::uint16_t or_mask = 0;         // FC16
    std::uint16_t write_address = 0;   // FC17
    std::uint16_t write_quantity = 0;  // FC17
    std::uint16_t sub_function = 0;    // FC08
    std::uint8_t mei_type = 0;         // FC2B
    std::uint8_t device_id_code = 0;   // FC2B/0E: 1 basic, 2 regular, 3 extended, 4 one object
    std::uint8_t object_id = 0;        // FC2B/0E
    // FC0F: packed coils; FC10/17: register values big-endian; FC08: data after sub-function;
    // FC14/15: the sub-request bytes after the byte count (iterate with FileRecordIterator).
    Bytes payload;
};

// One response PDU (normal or exception).
struct Response {
    std::uint8_t function = 0;                      // without the exception bit
    ExceptionCode exception = ExceptionCode::None;  // != None: exception response
    std::uint16_t address = 0;                      // FC05,06,0F,10,16 echo
    std::uint16_t quantity = 0;                     // FC0F,10 echo
    std::uint16_t value = 0;                        // FC05,06 echo
    std::uint16_t and_mask = 0;                     // FC16 echo
    std::uint16_t or_mask = 0;                      // FC16 echo
    std::uint16_t sub_function = 0;                 // FC08 echo
    std::uint8_t exception_status = 0;              // FC07
    std::uint16_t status = 0;                       // FC0B/0C
    std::uint16_t event_count = 0;                  // FC0B/0C
    std::uint16_t message_count = 0;                // FC0C
    std::uint16_t fifo_count = 0;                   // FC18
    std::uint8_t mei_type = 0;                      // FC2B
    std::uint8_t device_id_code = 0;                // FC2B/0E
    std::uint8_t conformity_level = 0;              // FC2B/0E
    std::uint8_t more_follows = 0;                  // FC2B/0E: 0x00 or 0xFF
    std::uint8_t next_object_id = 0;                // FC2B/0E
    std::uint8_t object_count = 0;                  // FC2B/0E
    // FC01-04,17: data bytes after the byte count; FC08: data after sub-function;
    // FC0C: events; FC11: server id bytes; FC14: sub-responses; FC15: echo of sub-requests;
    // FC18: FIFO values (big-endian); FC2B/0E: object list (id, length, value)*.
    Bytes payload;
};

// Result of decoding a request. `exception` is what a conforming server must answer
// (01, 02 or 03), or None when the request is well-formed.
struct RequestStatus {
    CodecError error = CodecError::Ok;
    ExceptionCode exception = ExceptionCode::None;
    constexpr bool ok() const noexcept { return error == CodecError::Ok; }
};

// Result of encoding: bytes written, or an error (BufferTooSmall, InvalidArgument).
struct EncodeResult {
    std::size_t size = 0;
    CodecError error = CodecError::Ok;
    constexpr bool ok() const noexcept { return error == CodecError::Ok; }
};

// Decodes one request PDU (function code first). Checks lengths, byte counts and every
// quantity limit; on failure `out` is partially filled (function at least, where present).
RequestStatus decode_request(Bytes pdu, Request& out) noexcept;

// Decodes one response PDU. Exception responses set `exception`.
CodecError decode_response(Bytes pdu, Response& out) noexcept;

// Encodes a request PDU into `out`. Validates limits (InvalidArgument when broken) unless
// `allow_invalid` is set, which the fuzzer uses to build out-of-spec requests on purpose.
EncodeResult encode_request(const Request& req, MutableBytes out,
                            bool allow_invalid = false) noexcept;

// Encodes a response PDU (or an exception response when `exception != None`).
EncodeResult encode_response(const Response& rsp, MutableBytes out) noexcept;

// Encodes an exception response: function|0x80, code.
EncodeResult encode_exception(std::uint8_t function, ExceptionCode code, MutableBytes out) noexcept;

// Fast paths for the load engine's most common requests (no validation beyond size).
EncodeResult encode_read_request(std::uint8_t function, std::uint16_t address,
                                 std::uint16_t quantity, MutableBytes out) noexcept;

// Size of a request PDU of function `fc` for `quantity` items (FC17: `write_quantity`
// registers written) as a generator builds it: FC08 with one data word, FC2B reading device
// identification. kMaxPdu when the caller's data decides (FC14/15) or the code is unknown.
std::size_t request_pdu_size(std::uint8_t fc, std::uint16_t quantity,
                             std::uint16_t write_quantity) noexcept;

// Expected byte count of a read response for the given request, used to match responses.
// Returns -1 when the function has no fixed data size.
int expected_read_byte_count(const Request& req) noexcept;

// Iterates FC14/15 sub-requests (and FC15 responses): reference type, file, record, length,
// and for FC15 the record data.
struct FileSubRequest {
    std::uint8_t reference_type = 0;
    std::uint16_t file_number = 0;
    std::uint16_t record_number = 0;
    std::uint16_t record_length = 0;  // in registers
    Bytes record_data;                // FC15 only: record_length * 2 bytes
};
class FileRecordIterator {
  public:
    // `with_data`: true for FC15 (sub-requests carry data), false for FC14.
    FileRecordIterator(Bytes sub_requests, bool with_data) noexcept
        : rest_(sub_requests), with_data_(with_data) {}
    // Returns Ok with the next sub-request, Empty at the end, or an error.
    CodecError next(FileSubRequest& out) noexcept;

  private:
    Bytes rest_;
    bool with_data_;
};

// Writes one FC14/15 sub-request into `out`: reference type, file, record, length and (FC15)
// `record_data`, as many bytes as it carries. The bytes a Request's payload holds after the
// byte count; several sub-requests are written one after another.
EncodeResult encode_file_sub_request(const FileSubRequest& sub, MutableBytes out) noexcept;

// Iterates FC14 response sub-responses: (length, reference type, data).
struct FileSubResponse {
    std::uint8_t reference_type = 0;
    Bytes record_data;
};
class FileResponseIterator {
  public:
    explicit FileResponseIterator(Bytes sub_responses) noexcept : rest_(sub_responses) {}
    CodecError next(FileSubResponse& out) noexcept;

  private:
    Bytes rest_;
};

// Iterates FC2B/0E objects: (object id, length, value).
struct DeviceIdObject {
    std::uint8_t id = 0;
    Bytes value;
};
class DeviceIdObjectIterator {
  public:
    explicit DeviceIdObjectIterator(Bytes objects) noexcept : rest_(objects) {}
    CodecError next(DeviceIdObject& out) noexcept;

  private:
    Bytes rest_;
};

}  // namespace mbstorm::codec
