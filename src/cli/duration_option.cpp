#include "cli/duration_option.hpp"

#include "stats/duration_text.hpp"

namespace mbstorm::cli {

CLI::Option* add_duration_option(CLI::App* cmd, const std::string& name, std::uint64_t& ns,
                                 const std::string& description) {
    return cmd
        ->add_option_function<std::string>(
            name,
            [&ns, name](const std::string& text) {
                if (!stats::parse_duration_ns(text, ns))
                    throw CLI::ValidationError(
                        name, "'" + text + "' is not a duration (e.g. 500us, 2ms, 1.5s, 2m, 1h)");
            },
            description)
        ->type_name("DURATION");
}

CLI::Option* add_rate_option(CLI::App* cmd, const std::string& name, double& fraction,
                             const std::string& description) {
    return cmd
        ->add_option_function<std::string>(
            name,
            [&fraction, name](const std::string& text) {
                std::string t = text;
                bool percent = !t.empty() && t.back() == '%';
                if (percent) t.pop_back();
                double v = -1;
                try {
                    std::size_t used = 0;
                    v = std::stod(t, &used);
                    if (used != t.size()) v = -1;
                } catch (...) {
                    v = -1;
                }
                if (percent) v /= 100.0;
                if (!(v >= 0.0 && v <= 1.0))
                    throw CLI::ValidationError(
                        name, "'" + text + "' is not a rate in 0..1 (e.g. 0.01 or 1%)");
                fraction = v;
            },
            description)
        ->type_name("RATE");
}

}  // namespace mbstorm::cli
