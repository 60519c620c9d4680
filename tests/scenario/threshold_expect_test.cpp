#include <gtest/gtest.h>

#include <array>

#include "scenario/expect.hpp"
#include "scenario/threshold.hpp"

namespace mbstorm::scenario {
namespace {

ThresholdSpec parse(const char* text) {
    Result<ThresholdSpec> spec = parse_threshold(text);
    EXPECT_TRUE(spec.ok()) << text << ": " << spec.error().text();
    return spec.ok() ? std::move(spec).value() : ThresholdSpec{};
}

stats::RunResult sample_run() {
    stats::RunResult run;
    for (int i = 1; i <= 100; ++i)
        run.latency.record(static_cast<std::uint64_t>(i) * 100'000);  // 0.1..10ms
    for (int i = 0; i < 990; ++i) run.counters.record(stats::Outcome::Ok);
    for (int i = 0; i < 7; ++i) run.counters.record_exception(0x02);
    for (int i = 0; i < 3; ++i) run.counters.record(stats::Outcome::Timeout);
    run.metadata.measured_duration_ns = 2'000'000'000;  // 1000 completed in 2 s
    stats::OperationResult op;
    op.name = "read";
    op.latency.record(1'000'000);
    op.counters.record(stats::Outcome::ValueMismatch);
    op.counters.record(stats::Outcome::Ok);
    run.operations.push_back(op);
    return run;
}

TEST(Threshold, ParsesTheDocumentedForms) {
    EXPECT_DOUBLE_EQ(parse("p99 < 5ms").limit, 5e6);
    EXPECT_DOUBLE_EQ(parse("p99.9<20ms").percentile, 99.9);
    EXPECT_DOUBLE_EQ(parse("  max <= 1.5s ").limit, 1.5e9);
    EXPECT_DOUBLE_EQ(parse("mean < 250us").limit, 250e3);
    EXPECT_DOUBLE_EQ(parse("error_rate < 0.1%").limit, 0.001);
    EXPECT_DOUBLE_EQ(parse("error_rate < 0.002").limit, 0.002);
    EXPECT_DOUBLE_EQ(parse("throughput > 50000/s").limit, 50000);
    EXPECT_DOUBLE_EQ(parse("throughput >= 1.5M/s").limit, 1.5e6);
    EXPECT_EQ(parse("exceptions[0x0B] == 0").exception_code, 0x0B);
    EXPECT_EQ(parse("exceptions != 3").exception_code, -1);
    EXPECT_EQ(parse("errors == 0").comparison, Comparison::Equal);
    EXPECT_EQ(parse("p99 < 5ms").text, "p99 < 5ms");
    EXPECT_EQ(parse("p99<5ms").text, "p99 < 5ms");
}

TEST(Threshold, ARefusalIsInvalidInputNamingTheForms) {
    const Error e = parse_threshold("p99 5ms").error();
    EXPECT_EQ(e.code(), ErrorCode::InvalidInput);
    EXPECT_EQ(e.place(), "");  // the caller knows where it was written (a file, --threshold)
    EXPECT_NE(e.message().find("has no comparison"), std::string::npos) << e.text();
    EXPECT_NE(e.message().find("<, <=, >, >=, ==, !="), std::string::npos) << e.text();
}

TEST(Threshold, EvaluatesOverallAndPerOperation) {
    const stats::RunResult run = sample_run();
    auto eval = [&](const char* text, const char* op = "") {
        ThresholdSpec spec = parse(text);
        spec.operation = op;
        return evaluate_threshold(spec, run);
    };
    EXPECT_TRUE(eval("p50 < 6ms").passed);
    EXPECT_FALSE(eval("p99 < 5ms").passed);
    EXPECT_NE(eval("p99 < 5ms").observed_text.find("ms"), std::string::npos);
    EXPECT_TRUE(eval("max < 11ms").passed);
    EXPECT_TRUE(eval("min < 1ms").passed);
    EXPECT_TRUE(eval("error_rate < 1.1%").passed);  // 10 / 1000
    EXPECT_FALSE(eval("error_rate < 0.9%").passed);
    EXPECT_EQ(eval("error_rate < 1%").observed_text, "1%");
    EXPECT_TRUE(eval("throughput > 499/s").passed);  // 1000 in 2 s
    EXPECT_FALSE(eval("throughput > 501/s").passed);
    EXPECT_TRUE(eval("exceptions[02] == 7").passed);
    EXPECT_TRUE(eval("exceptions[03] == 0").passed);
    EXPECT_TRUE(eval("exceptions == 7").passed);
    EXPECT_TRUE(eval("timeouts == 3").passed);
    EXPECT_TRUE(eval("errors == 10").passed);
    EXPECT_TRUE(eval("transactions == 1000").passed);
    EXPECT_TRUE(eval("mismatches == 1", "read").passed);
    EXPECT_TRUE(eval("mismatches == 0").passed);
    EXPECT_EQ(eval("p99 < 5ms", "read").expression, "read: p99 < 5ms");
    EXPECT_FALSE(eval("errors == 0", "missing").passed);
}

// Observed latencies print µs like every report (they printed "405us").
TEST(Threshold, ObservedMicrosecondsPrintAsEverywhereElse) {
    EXPECT_EQ(format_metric_value(Metric::Percentile, 405e3), "405µs");
    EXPECT_EQ(format_metric_value(Metric::Max, 3.1e6), "3.1ms");
    EXPECT_EQ(format_metric_value(Metric::Mean, 850), "850ns");
}

TEST(Threshold, StrayResponsesFailAnErrorCountButAreNoTransactions) {
    stats::RunResult run = sample_run();
    run.counters.record(stats::Outcome::UnknownId);
    run.counters.record(stats::Outcome::DuplicateId);
    EXPECT_TRUE(evaluate_threshold(parse("errors == 12"), run).passed);
    EXPECT_TRUE(evaluate_threshold(parse("transactions == 1000"), run).passed);
    EXPECT_TRUE(evaluate_threshold(parse("throughput < 501/s"), run).passed);
    EXPECT_EQ(evaluate_threshold(parse("error_rate < 1%"), run).observed_text, "1%");
}

TEST(Threshold, NoSamplesFailsLatencyAndRateLimits) {
    const stats::RunResult empty;
    EXPECT_FALSE(evaluate_threshold(parse("p99 < 1s"), empty).passed);
    EXPECT_EQ(evaluate_threshold(parse("p99 < 1s"), empty).observed_text, "no samples");
    EXPECT_FALSE(evaluate_threshold(parse("error_rate < 100%"), empty).passed);
    EXPECT_TRUE(evaluate_threshold(parse("errors == 0"), empty).passed);
}

TEST(Expect, ChecksRegistersAndBits) {
    Expectation e;
    e.active = true;
    e.value = 0x1234;
    load::RequestInfo req;
    req.function = 0x03;
    req.address = 10;
    req.quantity = 2;
    std::array<std::uint8_t, 4> regs{0x12, 0x34, 0x12, 0x34};
    codec::Response resp;
    resp.payload = codec::Bytes(regs);
    EXPECT_TRUE(response_matches(e, req, resp));
    regs[3] = 0x35;
    EXPECT_FALSE(response_matches(e, req, resp));

    Expectation range;
    range.active = true;
    range.min = 0x1200;
    range.max = 0x1240;
    EXPECT_TRUE(response_matches(range, req, resp));
    regs[0] = 0x13;
    EXPECT_FALSE(response_matches(range, req, resp));

    Expectation list;
    list.active = true;
    list.first_address = 10;
    list.values = {0x1334, 0x1235};
    EXPECT_TRUE(response_matches(list, req, resp));
    req.address = 11;  // now register 11 must be 0x1235 and 12 is past the list
    req.quantity = 1;
    EXPECT_FALSE(response_matches(list, req, resp));

    // Short payload: a mismatch, never a read past the buffer.
    req.quantity = 3;
    EXPECT_FALSE(response_matches(e, req, resp));

    Expectation bits;
    bits.active = true;
    bits.value = 1;
    load::RequestInfo coil_req;
    coil_req.function = 0x01;
    coil_req.quantity = 3;
    std::array<std::uint8_t, 1> packed{0x07};
    codec::Response coils;
    coils.payload = codec::Bytes(packed);
    EXPECT_TRUE(response_matches(bits, coil_req, coils));
    packed[0] = 0x05;
    EXPECT_FALSE(response_matches(bits, coil_req, coils));

    Expectation inactive;
    EXPECT_TRUE(response_matches(inactive, coil_req, coils));
}

TEST(Expect, VerifierOnlyWhenSomethingIsChecked) {
    std::vector<Expectation> none(2);
    EXPECT_EQ(make_verifier(none).check, nullptr);
    none[1].active = true;
    none[1].value = 1;
    const load::ResponseVerifier v = make_verifier(none);
    ASSERT_NE(v.check, nullptr);
    load::RequestInfo req;
    req.op_index = 0;  // op 0 is not checked
    req.function = 0x03;
    req.quantity = 1;
    std::array<std::uint8_t, 2> reg{0, 9};
    codec::Response resp;
    resp.payload = codec::Bytes(reg);
    EXPECT_TRUE(v.check(v.context, req, resp));
    req.op_index = 1;
    EXPECT_FALSE(v.check(v.context, req, resp));
}

}  // namespace
}  // namespace mbstorm::scenario
