#pragma once
// Test support: whole-file reads and writes, in binary mode.
#include <fstream>
#include <iterator>
#include <string>

namespace msii::test {

/// The bytes of the file at @p path; "" if it cannot be opened.
inline std::string readFile(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// Creates or truncates the file at @p path and writes @p bytes to it.
inline void writeFile(const std::string& path, const std::string& bytes)
{
    std::ofstream out(path, std::ios::binary);
    out.write(bytes.data(), std::streamsize(bytes.size()));
}

} // namespace msii::test
