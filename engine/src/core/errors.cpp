#include <msii/core/errors.h>

#include <cstdint>
#include <cstdio>

namespace msii {

namespace {

bool readable(std::uint32_t cp)
{
    static constexpr std::uint32_t kRanges[][2] = {
        {0x00A1, 0x00AC}, {0x00AE, 0x017F},                     // Latin-1 signs and letters (no soft hyphen)
        {0x0391, 0x03A1}, {0x03A3, 0x03A9}, {0x03B1, 0x03C9},   // Greek letters
        {0x0400, 0x045F},                                       // Cyrillic
        {0x2010, 0x2027}, {0x2030, 0x205E},                     // dashes, quotes, bullets, ellipsis, primes
        {0x2070, 0x2071}, {0x2074, 0x208E},                     // super- and subscripts
        {0x2190, 0x22FF}, {0x25A0, 0x25FF},                     // arrows, mathematical operators, shapes
        {0x4E00, 0x9FFF},                                       // CJK ideographs
    };
    for (const auto& r : kRanges)
        if (cp >= r[0] && cp <= r[1]) return true;
    return false;
}

} // namespace

std::string printableLine(const std::string& text)
{
    std::string out;
    out.reserve(text.size());
    const auto escape = [&](unsigned char c) {
        char hex[8];
        std::snprintf(hex, sizeof hex, "\\x%02X", c);
        out += hex;
    };
    for (std::size_t i = 0; i < text.size();) {
        const unsigned char c = static_cast<unsigned char>(text[i]);
        if (c < 0x80) {
            if (c < 0x20 || c == 0x7F) escape(c);
            else out += char(c);
            ++i;
            continue;
        }
        // A well-formed UTF-8 sequence (no overlong forms, no surrogates) is kept whole.
        const std::size_t n = c >= 0xC2 && c <= 0xDF ? 2 : c >= 0xE0 && c <= 0xEF ? 3 : c >= 0xF0 && c <= 0xF4 ? 4 : 0;
        bool ok = n > 0 && i + n <= text.size();
        for (std::size_t k = 1; ok && k < n; ++k) ok = (static_cast<unsigned char>(text[i + k]) & 0xC0) == 0x80;
        if (ok && n == 3) {
            const unsigned char d = static_cast<unsigned char>(text[i + 1]);
            ok = !(c == 0xE0 && d < 0xA0) && !(c == 0xED && d >= 0xA0);
        }
        if (ok && n == 4) {
            const unsigned char d = static_cast<unsigned char>(text[i + 1]);
            ok = !(c == 0xF0 && d < 0x90) && !(c == 0xF4 && d >= 0x90);
        }
        // Of the other characters, those of the scripts and signs people and msii's messages
        // write (Latin, Greek, Cyrillic letters; dashes, quotes, arrows, mathematical signs,
        // shapes; CJK ideographs): not the control, format, separator and unassigned code
        // points that would break or hide part of the line.
        if (ok) {
            std::uint32_t cp = c & (n == 2 ? 0x1F : n == 3 ? 0x0F : 0x07);
            for (std::size_t k = 1; k < n; ++k) cp = (cp << 6) | (static_cast<unsigned char>(text[i + k]) & 0x3F);
            ok = readable(cp);
        }
        if (!ok) {
            escape(c);
            ++i;
            continue;
        }
        out.append(text, i, n);
        i += n;
    }
    return out;
}

} // namespace msii
