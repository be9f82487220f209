#pragma once
/// @file errors.h
/// @brief The exception hierarchy of msii. Tools catch these at main(), print one line
/// ("msii: error: <what>") and exit non-zero.

#include <stdexcept>
#include <string>

namespace msii {

/// Base of all errors msii reports to the user; what() is one complete sentence.
class Error : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// The input (a mesh, a parameter, a feature file) cannot be used as given.
class InvalidInputError : public Error {
public:
    using Error::Error;
};

/// A computation would take more memory than it may use (invariants/invariants.h, the
/// estimate of its surface); thrown before anything large is allocated, so that a caller
/// may try smaller pieces (terrain/dem_compute.h splits such a window).
class MemoryLimitError : public InvalidInputError {
public:
    using InvalidInputError::InvalidInputError;
};

/// A file cannot be read or written.
class IOError : public Error {
public:
    using Error::Error;
};

/// @p text as one printable line, for messages that quote bytes of a file: control
/// characters (newlines included) and bytes that are not UTF-8 become "\xNN", so that an
/// error stays the one line msii promises.
std::string printableLine(const std::string& text);

} // namespace msii
