#pragma once
/// @file view_server.h
/// @brief The web server of `msii view`: one folder's regular files, read-only, on the
/// loopback interface only (cpp-httplib, Debian's libcpp-httplib-dev).
#include <atomic>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>

namespace msii::tools {

/// The file a request for the (percent-decoded) URL path @p urlPath names inside
/// @p canonicalRoot (a canonical folder), or nothing: for a path that does not start with
/// "/", holds a NUL, a backslash or a ".." component, is absolute after its first "/", or
/// leads (through symbolic links too) to anything but a regular file inside the folder.
/// "/" and paths ending in "/" name that folder's index.html.
std::optional<std::filesystem::path> resolveRequestPath(const std::filesystem::path& canonicalRoot,
                                                        const std::string& urlPath);

/// The Content-Type of a file, by its extension (text types in UTF-8).
std::string contentTypeOf(const std::filesystem::path& file);

struct ServeOptions {
    int port = 0;                        ///< 0: a free port chosen by the system
    /// Called once the server listens, with its port (before any request is answered).
    std::function<void(int port)> onListening;
    /// The server stops (and serveFolder returns) soon after this is set.
    const std::atomic<bool>* stop = nullptr;
};

/// Serves the regular files of @p folder on http://127.0.0.1:PORT/ until options.stop is
/// set: GET and HEAD only (other methods get 405), anything else of resolveRequestPath's
/// refusals 404, and requests naming another host than 127.0.0.1 or localhost (a web page
/// that rebinds its own name to this address) 403.
/// @throw IOError if the port cannot be had (in use, or not allowed).
void serveFolder(const std::string& folder, const ServeOptions& options);

} // namespace msii::tools
