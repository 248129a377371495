// PointRT prt-import: input text quoted in one-line error messages, safe to print.
#pragma once

#include <string>
#include <string_view>

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

}  // namespace prt::pre::import
