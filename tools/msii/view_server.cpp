#include "view_server.h"

#include <msii/core/errors.h>

#include <httplib.h>

#include <chrono>
#include <fstream>
#include <map>
#include <memory>
#include <thread>
#include <vector>

namespace msii::tools {

namespace fs = std::filesystem;

std::optional<fs::path> resolveRequestPath(const fs::path& canonicalRoot, const std::string& urlPath)
{
    if (urlPath.empty() || urlPath[0] != '/') return std::nullopt;
    if (urlPath.find('\0') != std::string::npos || urlPath.find('\\') != std::string::npos) return std::nullopt;
    std::string relative = urlPath.substr(1);
    if (relative.empty() || relative.back() == '/') relative += "index.html";
    const fs::path path(relative);
    if (path.is_absolute() || path.has_root_name() || path.has_root_directory()) return std::nullopt;
    for (const fs::path& part : path)
        if (part == "..") return std::nullopt;
    // The file itself, its links followed: it must still lie inside the folder.
    std::error_code ec;
    const fs::path file = fs::canonical(canonicalRoot / path, ec);
    if (ec) return std::nullopt;
    auto r = canonicalRoot.begin(), f = file.begin();
    for (; r != canonicalRoot.end(); ++r, ++f)
        if (f == file.end() || *r != *f) return std::nullopt;
    if (!fs::is_regular_file(file, ec)) return std::nullopt;
    return file;
}

std::string contentTypeOf(const fs::path& file)
{
    static const std::map<std::string, std::string> types{
        {".html", "text/html; charset=utf-8"},
        {".js", "text/javascript; charset=utf-8"},
        {".mjs", "text/javascript; charset=utf-8"},
        {".css", "text/css; charset=utf-8"},
        {".json", "application/json"},
        {".bin", "application/octet-stream"},
        {".png", "image/png"},
        {".svg", "image/svg+xml"},
        {".txt", "text/plain; charset=utf-8"},
        {"", "text/plain; charset=utf-8"},  // LICENSE
    };
    const auto it = types.find(file.extension().string());
    return it == types.end() ? "application/octet-stream" : it->second;
}

namespace {

/// Whether the Host header names this server: 127.0.0.1, localhost or [::1], with our port
/// or none. Anything else is a page that points its own name at 127.0.0.1 (DNS rebinding).
bool isLocalHost(const httplib::Request& req, int port)
{
    if (!req.has_header("Host")) return true;
    const std::string host = req.get_header_value("Host");
    const std::string p = ":" + std::to_string(port);
    for (const char* name : {"127.0.0.1", "localhost", "[::1]"})
        if (host == name || host == name + p) return true;
    return false;
}

void sendFile(const fs::path& file, httplib::Response& res)
{
    std::error_code ec;
    const std::uintmax_t size = fs::file_size(file, ec);
    auto in = std::make_shared<std::ifstream>(file, std::ios::binary);
    if (ec || !*in) {
        res.status = 404;
        res.set_content("not found\n", "text/plain; charset=utf-8");
        return;
    }
    res.set_header("Cache-Control", "no-cache");
    res.set_header("X-Content-Type-Options", "nosniff");
    // Streamed in pieces: data.bin may be hundreds of MB.
    res.set_content_provider(std::size_t(size), contentTypeOf(file),
                             [in](std::size_t offset, std::size_t length, httplib::DataSink& sink) {
                                 std::vector<char> buffer(std::min<std::size_t>(length, 1 << 20));
                                 in->seekg(std::streamoff(offset));
                                 in->read(buffer.data(), std::streamsize(buffer.size()));
                                 const std::streamsize got = in->gcount();
                                 if (got <= 0) return false;
                                 return sink.write(buffer.data(), std::size_t(got));
                             });
}

} // namespace

void serveFolder(const std::string& folder, const ServeOptions& options)
{
    const fs::path root = fs::canonical(folder);
    httplib::Server server;
    // The page stops reading data.bin while it draws its first frame (seconds, with
    // software WebGL): the library's 5 s for a blocked write would cut it off.
    server.set_write_timeout(300, 0);
    int port = options.port;
    server.set_pre_routing_handler([&port](const httplib::Request& req, httplib::Response& res) {
        if (req.method != "GET" && req.method != "HEAD") {
            res.status = 405;
            res.set_header("Allow", "GET, HEAD");
            res.set_content("only GET and HEAD\n", "text/plain; charset=utf-8");
            return httplib::Server::HandlerResponse::Handled;
        }
        if (!isLocalHost(req, port)) {
            res.status = 403;
            res.set_content("this server answers requests for 127.0.0.1 and localhost only\n",
                            "text/plain; charset=utf-8");
            return httplib::Server::HandlerResponse::Handled;
        }
        return httplib::Server::HandlerResponse::Unhandled;
    });
    server.Get(".*", [&root](const httplib::Request& req, httplib::Response& res) {
        const std::optional<fs::path> file = resolveRequestPath(root, req.path);
        if (!file) {
            res.status = 404;
            res.set_content("not found\n", "text/plain; charset=utf-8");
            return;
        }
        sendFile(*file, res);
    });
    const bool bound = port == 0 ? (port = server.bind_to_any_port("127.0.0.1")) > 0
                                 : server.bind_to_port("127.0.0.1", port);
    if (!bound)
        throw IOError("cannot listen on 127.0.0.1:" + std::to_string(options.port) +
                      " (the port is in use or not allowed; --port 0 picks a free one)");
    if (options.onListening) options.onListening(port);
    std::atomic<bool> done{false};
    std::thread watcher([&] {
        // Until listen returns: a stop asked for before it ran is asked again.
        while (!done) {
            if (options.stop && options.stop->load()) server.stop();
            std::this_thread::sleep_for(std::chrono::milliseconds(100));
        }
    });
    const bool listened = server.listen_after_bind();
    done = true;
    watcher.join();
    if (!listened && !(options.stop && options.stop->load()))
        throw IOError("the server on 127.0.0.1:" + std::to_string(port) + " stopped on an error");
}

} // namespace msii::tools
