#include "util/closest_name.hpp"

#include <algorithm>
#include <vector>

namespace mbstorm::util {

std::size_t edit_distance(std::string_view a, std::string_view b) {
    // Three rows of the dynamic-programming table: the swap looks two rows back.
    const std::size_t width = b.size() + 1;
    std::vector<std::size_t> before_previous(width), previous(width), current(width);
    for (std::size_t j = 0; j < width; ++j) previous[j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i) {
        current[0] = i;
        for (std::size_t j = 1; j < width; ++j) {
            const std::size_t substitution = a[i - 1] == b[j - 1] ? 0 : 1;
            current[j] =
                std::min({previous[j] + 1, current[j - 1] + 1, previous[j - 1] + substitution});
            if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
                current[j] = std::min(current[j], before_previous[j - 2] + 1);
        }
        std::swap(before_previous, previous);
        std::swap(previous, current);
    }
    return previous[b.size()];
}

std::string_view closest_name(std::string_view typed,
                              std::span<const std::string_view> candidates) {
    // Beyond this a "suggestion" is a guess: "xyz" is not a typo of "run".
    const std::size_t allowed = std::clamp<std::size_t>(typed.size() / 3, 1, 3);
    std::string_view best;
    std::size_t best_distance = allowed + 1;
    for (std::string_view candidate : candidates) {
        const std::size_t distance = edit_distance(typed, candidate);
        if (distance == 0) return {};
        // Not a rewrite of the whole word: "c" is no typo of "a".
        if (distance < best_distance && distance < typed.size()) {
            best = candidate;
            best_distance = distance;
        }
    }
    return best;
}

}  // namespace mbstorm::util
