// A coverage corpus on disk (fuzz --coverage --corpus DIR): one JSON file per entry, the case
// as finding.json writes one ({"class", "function", "steps": [...]}), named by its place in the
// corpus. A later run with the same DIR runs the saved entries first and goes on from there.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "netfuzz/case.hpp"
#include "util/error.hpp"

namespace mbstorm::netfuzz {

// Writes DIR/NNNNNN.json (creating DIR); an Io error when it cannot.
Error save_corpus_entry(const std::string& dir, std::size_t index, const Case& c);
// Every *.json in DIR, in name order (none when DIR does not exist). A file that is not a
// corpus entry is an InvalidInput error placed at its path: a corpus is not silently cut short.
Result<std::vector<Case>> load_corpus(const std::string& dir);

}  // namespace mbstorm::netfuzz
