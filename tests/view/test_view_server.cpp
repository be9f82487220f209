/// Tests of tools/msii/view_server.h: which URL paths name a file of the folder (the server
/// answers every other with 404), the content types, and a running server answering GET,
/// HEAD and nothing else (the browser test tests/view/test_view_browser.mjs asks it more).

#include "../../tools/msii/view_server.h"

#include "../support/temp_dir.h"

#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <fstream>
#include <thread>

using namespace msii::tools;
namespace fs = std::filesystem;

namespace {

/// A folder "view" with index.html, data.json and three/a.js, beside a file "secret.txt".
struct Site {
    msii::test::TempDir dir;
    fs::path root;
    Site()
    {
        fs::create_directories(dir.path() / "view" / "three");
        std::ofstream(dir.path() / "view" / "index.html") << "<html></html>";
        std::ofstream(dir.path() / "view" / "data.json") << "{}";
        std::ofstream(dir.path() / "view" / "three" / "a.js") << "//";
        std::ofstream(dir.path() / "secret.txt") << "secret";
        fs::create_symlink(dir.path() / "secret.txt", dir.path() / "view" / "out");
        fs::create_symlink("../secret.txt", dir.path() / "view" / "out-relative");
        fs::create_symlink(dir.path(), dir.path() / "view" / "dir-out");
        fs::create_symlink("data.json", dir.path() / "view" / "in");
        root = fs::canonical(dir.path() / "view");
    }
};

/// One raw HTTP/1.0 request; the status code of the answer.
int statusOf(int port, const std::string& requestLine, const std::string& host = "127.0.0.1")
{
    const int s = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(std::uint16_t(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::connect(s, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
        ::close(s);
        return -1;
    }
    const std::string req = requestLine + " HTTP/1.0\r\nHost: " + host + "\r\n\r\n";
    if (::send(s, req.data(), req.size(), 0) != ssize_t(req.size())) return -1;
    std::string answer;
    char buf[4096];
    ssize_t n;
    while ((n = ::recv(s, buf, sizeof buf, 0)) > 0) answer.append(buf, std::size_t(n));
    ::close(s);
    return answer.size() > 12 ? std::stoi(answer.substr(9, 3)) : -1;
}

} // namespace

TEST(ResolveRequestPath, FilesOfTheFolderOnly)
{
    Site site;
    EXPECT_EQ(resolveRequestPath(site.root, "/"), site.root / "index.html");
    EXPECT_EQ(resolveRequestPath(site.root, "/data.json"), site.root / "data.json");
    EXPECT_EQ(resolveRequestPath(site.root, "/three/a.js"), site.root / "three" / "a.js");
    EXPECT_EQ(resolveRequestPath(site.root, "/three//a.js"), site.root / "three" / "a.js");
    EXPECT_EQ(resolveRequestPath(site.root, "/in"), site.root / "data.json");  // a link inside
    const std::vector<std::string> refused{
        "", "data.json", "/../secret.txt", "/three/../../secret.txt", "/three/../data.json", "//etc/passwd",
        "/" + (site.dir.path() / "secret.txt").string(), "/out", "/out-relative", "/dir-out/secret.txt",
        "/three", "/missing", std::string("/data.json\0.png", 15), "/..\\secret.txt"};
    for (const std::string& p : refused) EXPECT_FALSE(resolveRequestPath(site.root, p).has_value()) << p;
    EXPECT_EQ(refused.size(), 14u);
}

TEST(ContentTypeOf, ThePagesTypes)
{
    EXPECT_EQ(contentTypeOf("index.html"), "text/html; charset=utf-8");
    EXPECT_EQ(contentTypeOf("a/viewer.js"), "text/javascript; charset=utf-8");
    EXPECT_EQ(contentTypeOf("viewer.css"), "text/css; charset=utf-8");
    EXPECT_EQ(contentTypeOf("data.json"), "application/json");
    EXPECT_EQ(contentTypeOf("data.bin"), "application/octet-stream");
    EXPECT_EQ(contentTypeOf("view.png"), "image/png");
    EXPECT_EQ(contentTypeOf("three/LICENSE"), "text/plain; charset=utf-8");
}

TEST(ServeFolder, AnswersGetAndHeadOnTheLoopbackUntilStopped)
{
    Site site;
    std::atomic<bool> stop{false};
    std::atomic<int> port{0};
    ServeOptions options;
    options.stop = &stop;
    options.onListening = [&](int p) { port = p; };
    std::thread server([&] { serveFolder((site.dir.path() / "view").string(), options); });
    for (int i = 0; i < 200 && port == 0; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    ASSERT_GT(port.load(), 0);
    EXPECT_EQ(statusOf(port, "GET /"), 200);
    EXPECT_EQ(statusOf(port, "HEAD /data.json"), 200);
    EXPECT_EQ(statusOf(port, "GET /%2e%2e/secret.txt"), 404);
    EXPECT_EQ(statusOf(port, "GET /..%2fsecret.txt"), 404);
    EXPECT_EQ(statusOf(port, "GET /out"), 404);
    EXPECT_EQ(statusOf(port, "POST /data.json"), 405);
    EXPECT_EQ(statusOf(port, "GET /data.json", "localhost:" + std::to_string(port)), 200);
    EXPECT_EQ(statusOf(port, "GET /data.json", "example.org"), 403);
    stop = true;
    server.join();  // returns: the server stopped
    EXPECT_EQ(statusOf(port, "GET /"), -1);
}
