#pragma once
/// @file version.h
/// @brief The program version recorded in every sidecar file.

namespace msii {

/// "MAJOR.MINOR.PATCH" of this build.
const char* versionString();

} // namespace msii
