// "Did you mean ...?" for every name a user types: subcommands, flags, YAML keys. Standard
// library only, so that every layer (yaml, scenario, cli) can use the one rule.
#pragma once

#include <cstddef>
#include <span>
#include <string_view>

namespace mbstorm::util {

// Edits (insert, delete, substitute, swap two neighbours) that turn `a` into `b`: the
// optimal-string-alignment distance. A swap counts once, so "rnu" is one edit from "run".
std::size_t edit_distance(std::string_view a, std::string_view b);

// The candidate nearest to `typed`, when near enough to be its typo: at most one edit per three
// characters typed (one for short words, at most three) and fewer than its length; the first
// of equally near ones.
// Empty when none is that near, or when `typed` is one of the candidates.
std::string_view closest_name(std::string_view typed, std::span<const std::string_view> candidates);

}  // namespace mbstorm::util
