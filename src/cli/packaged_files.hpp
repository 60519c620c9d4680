// Files mbstorm is packaged with (scenarios, the coverage runtime): where they are for this
// binary, and scenarios found by name (`mbstorm run quickstart`).
#pragma once

#include <string>
#include <string_view>

namespace mbstorm::cli {

// <prefix>/share/mbstorm/<what> beside an installed binary (<prefix>/bin/mbstorm), else the
// source tree's <what> for a binary run from its build folder; "" when neither exists.
std::string packaged_dir(std::string_view what);

// A scenario argument: the path as given when it exists, else NAME or NAME.yaml among the
// packaged scenarios; "" when none of them is a file.
std::string find_scenario(const std::string& arg);

}  // namespace mbstorm::cli
