// Thresholds as JUnit XML, and the XML escaping every report shares.
#include <gtest/gtest.h>

#include "report/junit.hpp"
#include "report/xml_escape.hpp"

namespace mbstorm::report {
namespace {

TEST(Junit, OneTestCasePerThresholdWithFailures) {
    stats::RunResult run;
    run.metadata.measured_duration_ns = 1'500'000'000;
    run.thresholds.push_back({"p99 < 5ms", 3e6, "3ms", true});
    run.thresholds.push_back({"error_rate < 0.1% & <more>", 0.5, "50%", false});
    const std::string xml = format_junit(run, "ci-gate");
    EXPECT_NE(xml.find("tests=\"2\" failures=\"1\""), std::string::npos) << xml;
    EXPECT_NE(xml.find("<testcase classname=\"mbstorm.ci-gate\" name=\"p99 &lt; 5ms\""),
              std::string::npos)
        << xml;
    EXPECT_NE(xml.find("&amp; &lt;more&gt;"), std::string::npos);
    EXPECT_NE(xml.find("<failure message=\"threshold breached: observed 50%\""), std::string::npos);
    EXPECT_NE(xml.find("time=\"1.500\""), std::string::npos);

    const std::string failed_run = format_junit(run, "x", "cannot connect");
    EXPECT_NE(failed_run.find("tests=\"3\" failures=\"2\""), std::string::npos) << failed_run;
    EXPECT_NE(failed_run.find("cannot connect"), std::string::npos);
}

TEST(XmlEscape, EscapesMarkupAndBlanksControlCharacters) {
    EXPECT_EQ(xml_escape("a<b>&\"c'd"), "a&lt;b&gt;&amp;&quot;c&#39;d");
    EXPECT_EQ(xml_escape(std::string("x\x01y\tz\n", 6)), "x y\tz\n");
}

}  // namespace
}  // namespace mbstorm::report
