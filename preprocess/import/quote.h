// PointRT prt-import: the text helpers of the header checks: input text quoted in one-line error
// messages (safe to print), and a header line split into words.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace prt::pre::import {

/// 'TEXT' with at most `max` characters; bytes that are not printable ASCII become '?', so a
/// binary file's bytes never reach the terminal.
inline std::string quoted(std::string_view text, std::size_t max = 40) {
    std::string out;
    out.reserve(std::min(text.size(), max) + 5);
    out.push_back('\'');
    for (std::size_t i = 0; i < text.size() && i < max; ++i) {
        const unsigned char c = static_cast<unsigned char>(text[i]);
        out.push_back(c >= 0x20 && c < 0x7F ? static_cast<char>(c) : '?');
    }
    if (text.size() > max) out += "...";
    out.push_back('\'');
    return out;
}

/// The words of a header line, split at spaces, tabs and carriage returns (PCD, PLY and OFF
/// headers).
inline std::vector<std::string_view> split_words(std::string_view line) {
    std::vector<std::string_view> words;
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
        const std::size_t start = i;
        while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
        if (i > start) words.push_back(line.substr(start, i - start));
    }
    return words;
}

}  // namespace prt::pre::import
