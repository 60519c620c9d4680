// Framing throughput: CRC-16, LRC, the MBAP splitter and RTU length inference.
#include <benchmark/benchmark.h>

#include <array>
#include <cstdint>
#include <random>
#include <vector>

#include "codec/ascii.hpp"
#include "codec/mbap.hpp"
#include "codec/rtu.hpp"

namespace {

using namespace mbstorm::codec;

std::vector<std::uint8_t> random_bytes(std::size_t n) {
    std::mt19937 rng(42);
    std::vector<std::uint8_t> v(n);
    for (auto& b : v) b = static_cast<std::uint8_t>(rng());
    return v;
}

void BM_Crc16(benchmark::State& state) {
    const auto data = random_bytes(static_cast<std::size_t>(state.range(0)));
    for (auto _ : state) benchmark::DoNotOptimize(crc16(data));
    state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) * state.range(0));
}
BENCHMARK(BM_Crc16)->Arg(8)->Arg(256)->Arg(4096);

void BM_Lrc(benchmark::State& state) {
    const auto data = random_bytes(static_cast<std::size_t>(state.range(0)));
    for (auto _ : state) benchmark::DoNotOptimize(lrc(data));
    state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) * state.range(0));
}
BENCHMARK(BM_Lrc)->Arg(256)->Arg(4096);

constexpr std::size_t kStreamBytes = 1 << 20;

// 1 MiB of pipelined 12-byte FC03 requests, the load a server sees from a busy client.
std::vector<std::uint8_t> fc3_stream() {
    std::vector<std::uint8_t> s;
    s.reserve(kStreamBytes);
    std::uint16_t tid = 0;
    while (s.size() + 12 <= kStreamBytes) {
        const std::uint8_t pdu[] = {0x03, 0x00, static_cast<std::uint8_t>(tid), 0x00, 0x0A};
        std::array<std::uint8_t, 12> adu{};
        encode_tcp_frame(tid++, 1, pdu, adu);
        s.insert(s.end(), adu.begin(), adu.end());
    }
    return s;
}

// Feeds the stream in the given chunk sizes (cycled) and counts frames.
void run_splitter(benchmark::State& state, const std::vector<std::uint8_t>& stream,
                  const std::vector<std::size_t>& chunks) {
    std::int64_t frames = 0;
    for (auto _ : state) {
        MbapSplitter sp;
        std::size_t off = 0;
        std::size_t i = 0;
        while (off < stream.size()) {
            const std::size_t n = std::min(chunks[i++ % chunks.size()], stream.size() - off);
            sp.feed(Bytes(stream.data() + off, n));
            off += n;
            TcpFrame f;
            while (sp.next(f) == MbapSplitter::Status::Frame) {
                benchmark::DoNotOptimize(f.pdu.data());
                ++frames;
            }
        }
    }
    state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) *
                            static_cast<std::int64_t>(stream.size()));
    state.counters["frames/s"] =
        benchmark::Counter(static_cast<double>(frames), benchmark::Counter::kIsRate);
}

void BM_SplitterChunks64K(benchmark::State& state) {
    run_splitter(state, fc3_stream(), {64 * 1024});
}
BENCHMARK(BM_SplitterChunks64K);

void BM_SplitterRandomChunks(benchmark::State& state) {
    // Sizes 1..1500 (Ethernet-segment-like), so most chunk ends cut a frame.
    std::mt19937 rng(7);
    std::uniform_int_distribution<std::size_t> size(1, 1500);
    std::vector<std::size_t> chunks(4096);
    for (auto& c : chunks) c = size(rng);
    run_splitter(state, fc3_stream(), chunks);
}
BENCHMARK(BM_SplitterRandomChunks);

void BM_SplitterMixedFrames64K(benchmark::State& state) {
    // Frames of 8..260 bytes, closer to a stream of mixed replies.
    std::mt19937 rng(3);
    std::uniform_int_distribution<std::size_t> pdu_size(1, limits::kMaxPdu);
    std::vector<std::uint8_t> s;
    std::array<std::uint8_t, limits::kMaxTcpAdu> adu{};
    std::vector<std::uint8_t> pdu(limits::kMaxPdu, 0x03);
    while (true) {
        const EncodeResult r = encode_tcp_frame(1, 1, Bytes(pdu.data(), pdu_size(rng)), adu);
        if (s.size() + r.size > kStreamBytes) break;
        s.insert(s.end(), adu.begin(), adu.begin() + static_cast<std::ptrdiff_t>(r.size));
    }
    run_splitter(state, s, {64 * 1024});
}
BENCHMARK(BM_SplitterMixedFrames64K);

// Heads of typical frames, for length inference.
std::vector<std::vector<std::uint8_t>> rtu_heads(bool requests) {
    const std::vector<std::vector<std::uint8_t>> req = {
        {0x11, 0x03, 0x00, 0x6B, 0x00, 0x03},
        {0x11, 0x10, 0x00, 0x01, 0x00, 0x02, 0x04},
        {0x11, 0x05, 0x00, 0xAC, 0xFF, 0x00},
        {0x11, 0x17, 0x00, 0x03, 0x00, 0x06, 0x00, 0x0E, 0x00, 0x03, 0x06},
    };
    const std::vector<std::vector<std::uint8_t>> rsp = {
        {0x11, 0x03, 0x06},
        {0x11, 0x10, 0x00, 0x01, 0x00, 0x02},
        {0x11, 0x83, 0x02},
        {0x11, 0x2B, 0x0E, 0x01, 0x01, 0x00, 0x00, 0x02, 0x00, 0x03, 'A', 'B', 'C', 0x01, 0x01,
         'X'},
    };
    return requests ? req : rsp;
}

void BM_RtuLength(benchmark::State& state) {
    const bool requests = state.range(0) == 0;
    const auto heads = rtu_heads(requests);
    for (auto _ : state) {
        for (const auto& h : heads) {
            benchmark::DoNotOptimize(requests ? rtu_request_length(h) : rtu_response_length(h));
        }
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * heads.size()));
    state.SetLabel(requests ? "requests" : "responses");
}
BENCHMARK(BM_RtuLength)->Arg(0)->Arg(1);

void BM_RtuEncodeDecode(benchmark::State& state) {
    const std::uint8_t pdu[] = {0x03, 0x00, 0x6B, 0x00, 0x03};
    std::array<std::uint8_t, limits::kMaxRtuAdu> out{};
    for (auto _ : state) {
        const EncodeResult r = encode_rtu_frame(0x11, pdu, out);
        RtuFrame f;
        benchmark::DoNotOptimize(decode_rtu_frame(Bytes(out.data(), r.size), f));
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}
BENCHMARK(BM_RtuEncodeDecode);

void BM_AsciiEncodeDecode(benchmark::State& state) {
    const std::uint8_t pdu[] = {0x03, 0x00, 0x6B, 0x00, 0x03};
    std::array<std::uint8_t, limits::kMaxAsciiAdu> text{};
    std::array<std::uint8_t, 256> bin{};
    for (auto _ : state) {
        const EncodeResult r = encode_ascii_frame(0x11, pdu, text);
        AsciiFrame f;
        benchmark::DoNotOptimize(decode_ascii_frame(Bytes(text.data(), r.size), bin, f));
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}
BENCHMARK(BM_AsciiEncodeDecode);

}  // namespace
