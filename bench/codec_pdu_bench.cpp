// PDU encode/decode cost per function code (requests and responses), with the load engine's
// and the server's hot paths singled out: FC03 request decode/encode and the 125-register
// FC03 response decode.
#include <benchmark/benchmark.h>

#include <cstdint>
#include <string>
#include <vector>

#include "codec/pdu.hpp"

namespace {

using namespace mbstorm::codec;

std::vector<std::uint8_t> hex(const char* text) {
    std::vector<std::uint8_t> out;
    for (const char* p = text; p[0] != '\0' && p[1] != '\0';) {
        if (p[0] == ' ') {
            ++p;
            continue;
        }
        out.push_back(static_cast<std::uint8_t>(std::stoi(std::string(p, 2), nullptr, 16)));
        p += 2;
    }
    return out;
}

void BM_Fc03RequestDecode(benchmark::State& state) {
    const std::uint8_t pdu[] = {0x03, 0x00, 0x6B, 0x00, 0x7D};
    Request req;
    for (auto _ : state) {
        benchmark::DoNotOptimize(pdu);
        const RequestStatus st = decode_request(Bytes(pdu, sizeof pdu), req);
        benchmark::DoNotOptimize(st);
        benchmark::DoNotOptimize(req);
    }
}
BENCHMARK(BM_Fc03RequestDecode);

void BM_Fc03RequestEncode(benchmark::State& state) {
    Request req;
    req.function = 0x03;
    req.address = 0x006B;
    req.quantity = 125;
    std::uint8_t out[260];
    for (auto _ : state) {
        benchmark::DoNotOptimize(req);
        const EncodeResult r = encode_request(req, MutableBytes(out, sizeof out));
        benchmark::DoNotOptimize(r);
        benchmark::ClobberMemory();
    }
}
BENCHMARK(BM_Fc03RequestEncode);

void BM_Fc03ReadRequestFastPath(benchmark::State& state) {
    std::uint8_t out[260];
    std::uint16_t address = 0;
    for (auto _ : state) {
        const EncodeResult r = encode_read_request(0x03, address++, 125, MutableBytes(out, 260));
        benchmark::DoNotOptimize(r);
        benchmark::ClobberMemory();
    }
}
BENCHMARK(BM_Fc03ReadRequestFastPath);

void BM_Fc03Response125Decode(benchmark::State& state) {
    std::vector<std::uint8_t> pdu{0x03, 250};
    for (int i = 0; i < 250; ++i) pdu.push_back(static_cast<std::uint8_t>(i));
    Response rsp;
    for (auto _ : state) {
        benchmark::DoNotOptimize(pdu.data());
        const CodecError e = decode_response(Bytes(pdu.data(), pdu.size()), rsp);
        benchmark::DoNotOptimize(e);
        benchmark::DoNotOptimize(rsp);
    }
}
BENCHMARK(BM_Fc03Response125Decode);

// The server's side: 125 registers copied into the send buffer behind the header.
void BM_Fc03Response125Encode(benchmark::State& state) {
    std::vector<std::uint8_t> regs(250, 0x5A);
    Response rsp;
    rsp.function = 0x03;
    rsp.payload = Bytes(regs.data(), regs.size());
    std::uint8_t out[260];
    for (auto _ : state) {
        const EncodeResult r = encode_response(rsp, MutableBytes(out, sizeof out));
        benchmark::DoNotOptimize(r);
        benchmark::ClobberMemory();
    }
}
BENCHMARK(BM_Fc03Response125Encode);

struct Vector {
    const char* name;
    const char* request;
    const char* response;
};

// One typical exchange per function code.
const Vector kVectors[] = {
    {"fc01", "01 00 13 00 25", "01 05 CD 6B B2 0E 1B"},
    {"fc02", "02 00 C4 00 16", "02 03 AC DB 35"},
    {"fc03", "03 00 6B 00 03", "03 06 02 2B 00 00 00 64"},
    {"fc04", "04 00 08 00 01", "04 02 00 0A"},
    {"fc05", "05 00 AC FF 00", "05 00 AC FF 00"},
    {"fc06", "06 00 01 00 03", "06 00 01 00 03"},
    {"fc07", "07", "07 6D"},
    {"fc08", "08 00 00 A5 37", "08 00 00 A5 37"},
    {"fc0b", "0B", "0B FF FF 01 08"},
    {"fc0c", "0C", "0C 08 00 00 01 08 01 21 20 00"},
    {"fc0f", "0F 00 13 00 0A 02 CD 01", "0F 00 13 00 0A"},
    {"fc10", "10 00 01 00 02 04 00 0A 01 02", "10 00 01 00 02"},
    {"fc11", "11", "11 03 0A FF 42"},
    {"fc14", "14 0E 06 00 04 00 01 00 02 06 00 03 00 09 00 02",
     "14 0C 05 06 0D FE 00 20 05 06 33 CD 00 40"},
    {"fc15", "15 0D 06 00 04 00 07 00 03 06 AF 04 BE 10 0D",
     "15 0D 06 00 04 00 07 00 03 06 AF 04 BE 10 0D"},
    {"fc16", "16 00 04 00 F2 00 25", "16 00 04 00 F2 00 25"},
    {"fc17", "17 00 03 00 06 00 0E 00 03 06 00 FF 00 FF 00 FF",
     "17 0C 00 FE 0A CD 00 01 00 03 00 0D 00 FF"},
    {"fc18", "18 04 DE", "18 00 06 00 02 01 B8 12 84"},
    {"fc2b", "2B 0E 01 00", "2B 0E 01 01 00 00 03 00 05 41 42 43 44 45 01 02 50 31 02 03 56 31 2E"},
    {"exception", "03 FF FF 00 02", "83 02"},  // request decode measures the rejection
};

void decode_request_bench(benchmark::State& state, const char* h) {
    const auto pdu = hex(h);
    Request req;
    for (auto _ : state) {
        benchmark::DoNotOptimize(decode_request(Bytes(pdu.data(), pdu.size()), req));
        benchmark::DoNotOptimize(req);
    }
}

void encode_request_bench(benchmark::State& state, const char* h) {
    const auto pdu = hex(h);
    Request req;
    if (!decode_request(Bytes(pdu.data(), pdu.size()), req).ok()) {
        state.SkipWithError("request does not decode");
        return;
    }
    std::uint8_t out[260];
    for (auto _ : state) {
        benchmark::DoNotOptimize(encode_request(req, MutableBytes(out, sizeof out)));
        benchmark::ClobberMemory();
    }
}

void decode_response_bench(benchmark::State& state, const char* h) {
    const auto pdu = hex(h);
    Response rsp;
    for (auto _ : state) {
        benchmark::DoNotOptimize(decode_response(Bytes(pdu.data(), pdu.size()), rsp));
        benchmark::DoNotOptimize(rsp);
    }
}

void encode_response_bench(benchmark::State& state, const char* h) {
    const auto pdu = hex(h);
    Response rsp;
    if (decode_response(Bytes(pdu.data(), pdu.size()), rsp) != CodecError::Ok) {
        state.SkipWithError("response does not decode");
        return;
    }
    std::uint8_t out[260];
    for (auto _ : state) {
        benchmark::DoNotOptimize(encode_response(rsp, MutableBytes(out, sizeof out)));
        benchmark::ClobberMemory();
    }
}

[[maybe_unused]] const bool kRegistered = [] {
    for (const Vector& v : kVectors) {
        const std::string n = v.name;
        benchmark::RegisterBenchmark(("BM_DecodeRequest/" + n).c_str(), decode_request_bench,
                                     v.request);
        if (n != "exception") {  // that request is the rejected one: nothing to encode
            benchmark::RegisterBenchmark(("BM_EncodeRequest/" + n).c_str(), encode_request_bench,
                                         v.request);
        }
        benchmark::RegisterBenchmark(("BM_DecodeResponse/" + n).c_str(), decode_response_bench,
                                     v.response);
        benchmark::RegisterBenchmark(("BM_EncodeResponse/" + n).c_str(), encode_response_bench,
                                     v.response);
    }
    return true;
}();

}  // namespace
