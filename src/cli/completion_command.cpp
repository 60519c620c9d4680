// `mbstorm completion bash|zsh`: a completion script made from the CLI definition itself
// (subcommands, their options, the values of enumerated options; zsh: with their help), so it
// never lags behind a new flag. Hidden from --help; the build installs both (CMakeLists.txt).
#include <fmt/format.h>

#include <cstdio>
#include <string>
#include <vector>

#include "cli/commands.hpp"
#include "cli/typed_values.hpp"
#include "codec/function_code.hpp"
#include "codec/values.hpp"

namespace mbstorm::cli {

namespace {

using Words = std::vector<std::string>;

// Options that read names through their own parsing rather than a CLI11 IsMember check: the
// one place that says which names they take, in any subcommand that has them.
Words names_parsed_by_hand(const std::string& option) {
    Words names;
    if (option == "--fc") {
        for (const codec::FunctionInfo& f : codec::public_functions()) names.emplace_back(f.name);
    } else if (option == "--table") {
        for (auto t : {codec::Table::Coils, codec::Table::DiscreteInputs,
                       codec::Table::InputRegisters, codec::Table::HoldingRegisters})
            names.emplace_back(codec::table_name(t));
    } else if (option == "--type") {
        for (auto t :
             {ValueType::U16, ValueType::I16, ValueType::U32, ValueType::I32, ValueType::U64,
              ValueType::I64, ValueType::F32, ValueType::F64, ValueType::String, ValueType::Bits})
            names.emplace_back(value_type_name(t));
    } else if (option == "--order") {
        for (auto o : {codec::WordOrder::ABCD, codec::WordOrder::CDAB, codec::WordOrder::BADC,
                       codec::WordOrder::DCBA})
            names.emplace_back(codec::word_order_name(o));
    }
    return names;
}

// An IsMember check shows in the option's type name as "TEXT:{a,b,c}".
Words member_values(const CLI::Option& opt) {
    const std::string type = opt.get_type_name();
    const auto open = type.find(":{");
    const auto close = type.find('}', open);
    Words values;
    if (open == std::string::npos || close == std::string::npos) return values;
    std::string set = type.substr(open + 2, close - open - 2);
    for (std::size_t start = 0; start <= set.size();) {
        auto comma = set.find(',', start);
        if (comma == std::string::npos) comma = set.size();
        if (comma > start) values.push_back(set.substr(start, comma - start));
        start = comma + 1;
    }
    return values;
}

std::string joined(const Words& words, const char* separator) {
    std::string out;
    for (const std::string& w : words) out.append(out.empty() ? "" : separator).append(w);
    return out;
}

struct OptionWords {
    Words names;       // "-c", "--connections"
    bool takes_value;  // not a flag
    Words values;      // what may follow it, empty when anything may
    std::string help;  // its description
    bool repeats = false;
};

std::vector<OptionWords> options_of(CLI::App& command) {
    std::vector<OptionWords> out;
    for (CLI::Option* opt : command.get_options()) {
        if (!opt->nonpositional() || opt->get_group().empty()) continue;
        OptionWords o;
        for (const std::string& s : opt->get_snames()) o.names.push_back("-" + s);
        for (const std::string& l : opt->get_lnames()) o.names.push_back("--" + l);
        o.takes_value = opt->get_expected_max() > 0;
        o.help = opt->get_description();
        o.repeats = opt->get_items_expected_max() > 1;
        if (o.takes_value) {
            o.values = member_values(*opt);
            if (o.values.empty()) o.values = names_parsed_by_hand("--" + opt->get_lnames().front());
        }
        out.push_back(std::move(o));
    }
    return out;
}

std::vector<CLI::App*> visible_subcommands(CLI::App& app) {
    return app.get_subcommands([](CLI::App* sub) { return !sub->get_group().empty(); });
}

// The case arm of one subcommand (or of the top level, named ""): its options, and after an
// option that takes a value, that value's choices or nothing (the shell then offers files).
std::string case_arm(const std::string& name, CLI::App& command) {
    std::string arm = fmt::format("        {})\n", name.empty() ? "\"\"" : name);
    Words all;
    Words free_values;  // options whose value may be anything
    std::string value_cases;
    for (const OptionWords& o : options_of(command)) {
        all.insert(all.end(), o.names.begin(), o.names.end());
        if (!o.takes_value) continue;
        if (o.values.empty()) {
            free_values.insert(free_values.end(), o.names.begin(), o.names.end());
        } else {
            value_cases += fmt::format("                {}) values=\"{}\" ;;\n",
                                       joined(o.names, " | "), joined(o.values, " "));
        }
    }
    if (!free_values.empty())
        value_cases += fmt::format("                {}) return ;;\n", joined(free_values, " | "));
    arm += fmt::format("            options=\"{}\"\n", joined(all, " "));
    if (name.empty()) {
        Words subs;
        for (CLI::App* sub : visible_subcommands(command)) subs.push_back(sub->get_name());
        arm += fmt::format("            [[ $cur == -* ]] || values=\"{}\"\n", joined(subs, " "));
    }
    if (!value_cases.empty())
        arm += "            case $prev in\n" + value_cases + "            esac\n";
    return arm + "            ;;\n";
}

std::string bash_completion_script(CLI::App& app) {
    std::string subcommand_names;
    std::string arms = case_arm("", app);
    for (CLI::App* sub : visible_subcommands(app)) {
        subcommand_names.append(subcommand_names.empty() ? "" : " | ").append(sub->get_name());
        arms += case_arm(sub->get_name(), *sub);
    }
    return fmt::format(
        R"(# bash completion for mbstorm: subcommands, options and the values of options that take
# names. Generated by `mbstorm completion bash` from the CLI's own definition; do not edit.
_mbstorm() {{
    local cur prev words cword split=false
    if declare -F _init_completion >/dev/null 2>&1; then
        _init_completion -s || return
    else
        words=("${{COMP_WORDS[@]}}")
        cword=$COMP_CWORD
        cur=${{COMP_WORDS[COMP_CWORD]}}
        prev=${{COMP_WORDS[COMP_CWORD - 1]}}
    fi
    local subcommand="" i
    for ((i = 1; i < cword; i++)); do
        case ${{words[i]}} in
            {}) subcommand=${{words[i]}}; break ;;
        esac
    done
    local options="" values=""
    case $subcommand in
{}    esac
    if [[ -n $values ]]; then
        mapfile -t COMPREPLY < <(compgen -W "$values" -- "$cur")
    elif [[ $split == false && $cur == -* ]]; then
        mapfile -t COMPREPLY < <(compgen -W "$options" -- "$cur")
    fi
}}
complete -o default -F _mbstorm mbstorm
)",
        subcommand_names, arms);
}

constexpr std::size_t kZshHelpWidth = 72;

// Text for a zsh completion spec: the help's first clause, inside single quotes, with what
// _arguments reads as syntax escaped (an option's help; a subcommand's, for _describe, needs
// only its quotes escaped).
std::string zsh_text(const std::string& help, bool for_arguments = true) {
    // The first clause, at most about a line.
    std::string first = help.substr(0, help.find_first_of(";\n"));
    if (first.size() > kZshHelpWidth) first = first.substr(0, first.rfind(' ', kZshHelpWidth));
    while (!first.empty() && (first.back() == ' ' || first.back() == ',')) first.pop_back();
    std::string out;
    for (const char c : first) {
        if (c == '\'') {
            out += "'\\''";
        } else {
            if (for_arguments && (c == '[' || c == ']' || c == ':' || c == '\\')) out += '\\';
            out += c;
        }
    }
    return out;
}

// One _arguments spec per name of each option: "--model=[open or closed loop]:value:(open
// closed)"; free values complete as files, as bash's default does.
std::string zsh_specs(CLI::App& command, const char* indent) {
    std::string specs;
    bool positional = false;
    for (CLI::Option* opt : command.get_options())
        positional = positional || (!opt->nonpositional() && opt->get_expected_max() > 0);
    for (const OptionWords& o : options_of(command)) {
        for (const std::string& name : o.names) {
            const bool long_name = name.rfind("--", 0) == 0;
            std::string spec = (o.repeats ? "*" : "") + name;
            if (o.takes_value && long_name) spec += "=";
            spec += "[" + zsh_text(o.help) + "]";
            if (o.takes_value)
                spec +=
                    o.values.empty() ? ":value:_files" : ":value:(" + joined(o.values, " ") + ")";
            specs += fmt::format(" \\\n{}'{}'", indent, spec);
        }
    }
    if (positional) specs += fmt::format(" \\\n{}'*:argument:_files'", indent);
    return specs;
}

std::string zsh_completion_script(CLI::App& app) {
    std::string listed, arms;
    for (CLI::App* sub : visible_subcommands(app)) {
        listed += fmt::format("        '{}:{}'\n", sub->get_name(),
                              zsh_text(sub->get_description(), false));
        arms += fmt::format("        {})\n            _arguments -s{}\n            ;;\n",
                            sub->get_name(), zsh_specs(*sub, "                "));
    }
    return fmt::format(
        R"(#compdef mbstorm
# zsh completion for mbstorm: subcommands, options with their help, and the values of options
# that take names. Generated by `mbstorm completion zsh` from the CLI's own definition; do not
# edit. Installed as _mbstorm in zsh's vendor-completions; or: source <(mbstorm completion zsh)
_mbstorm() {{
    local -a subcommands
    subcommands=(
{}    )
    if (( CURRENT == 2 )); then
        if [[ $words[CURRENT] == -* ]]; then
            _arguments -s{}
        else
            _describe -t commands 'mbstorm subcommand' subcommands
        fi
        return
    fi
    local subcommand=$words[2]
    shift words
    (( CURRENT-- ))
    curcontext="${{curcontext%:*:*}}:mbstorm-$subcommand:"
    case $subcommand in
{}    esac
}}
if [[ $funcstack[1] == _mbstorm ]]; then
    _mbstorm "$@"
else
    compdef _mbstorm mbstorm
fi
)",
        listed, zsh_specs(app, "                "), arms);
}

}  // namespace

void add_completion_command(CLI::App& app, Action& action) {
    auto shell = std::make_shared<std::string>();
    auto* cmd = app.add_subcommand("completion", "Print a shell completion script (bash or zsh)");
    cmd->group("");  // for packagers, not an everyday command
    cmd->add_option("shell", *shell, "the shell")
        ->required()
        ->check(CLI::IsMember({"bash", "zsh"}));
    cmd->callback([&app, &action, shell] {
        action = [&app, shell] {
            const std::string script =
                *shell == "zsh" ? zsh_completion_script(app) : bash_completion_script(app);
            std::fputs(script.c_str(), stdout);
            return kExitOk;
        };
    });
}

}  // namespace mbstorm::cli
