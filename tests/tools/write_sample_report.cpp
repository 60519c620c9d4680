// Writes a sample report (report.html, report.json, report.hgrm, report.txt) built from
// synthetic data into the given directory, e.g. for rendering the HTML in a browser.
//   write_sample_report <output-dir>
#include <cstdio>
#include <string>

#include "../report/sample_result.hpp"
#include "report/console.hpp"
#include "report/files.hpp"
#include "report/hgrm.hpp"
#include "report/html.hpp"
#include "report/json.hpp"

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: %s <output-dir>\n", argv[0]);
        return 2;
    }
    const std::string dir = argv[1];
    const auto result = mbstorm::report::testing::make_sample_result();
    const std::pair<const char*, std::string> files[] = {
        {"report.html", mbstorm::report::format_html(result)},
        {"report.json", mbstorm::report::format_json(result)},
        {"report.hgrm", mbstorm::report::format_hgrm(result.latency)},
        {"report.txt", mbstorm::report::format_console_report(result)},
    };
    for (const auto& [name, content] : files) {
        if (const mbstorm::Error error =
                mbstorm::report::write_text_file(dir + "/" + name, content);
            !error.ok()) {
            std::fprintf(stderr, "write_sample_report: %s\n", error.text().c_str());
            return 1;
        }
        std::printf("%s/%s\n", dir.c_str(), name);
    }
    return 0;
}
