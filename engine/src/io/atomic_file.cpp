#include <msii/io/atomic_file.h>

#include <msii/core/errors.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>

#include <csignal>
#include <cstdlib>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace msii {

namespace fs = std::filesystem;

namespace {

/// Folder of @p target ("." for a bare file name).
fs::path folderOf(const std::string& target)
{
    const fs::path parent = fs::path(target).parent_path();
    return parent.empty() ? fs::path(".") : parent;
}

[[noreturn]] void throwWriteError(const std::string& target, const std::string& reason)
{
    throw IOError("cannot write '" + target + "': " + reason + ".");
}

std::string errnoText(int code) { return std::strerror(code); }

/// The checks shared by checkWritable() and AtomicFile: the target names a file (not a
/// folder) and its folder exists. Permission problems surface when the file is opened.
void checkTarget(const std::string& target)
{
    if (target.empty()) throw IOError("cannot write an output file with an empty name.");
    if (fs::path(target).filename().empty())
        throwWriteError(target, "the path names a folder, not a file");

    struct stat st {};
    if (::stat(target.c_str(), &st) == 0) {
        if (S_ISDIR(st.st_mode)) throwWriteError(target, "it is a folder");
        if (!S_ISREG(st.st_mode)) throwWriteError(target, "it exists and is not a regular file");
    }

    const fs::path folder = folderOf(target);
    if (::stat(folder.c_str(), &st) != 0) {
        if (errno == ENOENT || errno == ENOTDIR)
            throwWriteError(target, "the folder '" + folder.string() + "' does not exist");
        throwWriteError(target, errnoText(errno));
    }
    if (!S_ISDIR(st.st_mode))
        throwWriteError(target, "'" + folder.string() + "' is not a folder");
}

// ---------------------------------------------------------------------------------------
// Temporary files open in this process, removed if it is interrupted (Ctrl-C, kill, a
// closed terminal) so that an interrupted run leaves nothing behind, not even a hidden
// temporary file (a tiled output can be many GB). The handler only calls unlink(), which is
// async-signal-safe, on paths held in lock-free slots.

constexpr int kTemporarySlots = 64;
std::atomic<char*> gTemporaries[kTemporarySlots];

extern "C" void removeTemporariesAndDie(int signal)
{
    for (auto& slot : gTemporaries)
        if (char* path = slot.load()) ::unlink(path);
    std::signal(signal, SIG_DFL);
    std::raise(signal);
}

/// Installs the handler for SIGINT, SIGTERM and SIGHUP where the program has none of its own.
void installInterruptCleanup()
{
    static const bool installed = [] {
        for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
            struct sigaction old {};
            if (::sigaction(sig, nullptr, &old) != 0 || old.sa_handler != SIG_DFL) continue;
            struct sigaction action {};
            action.sa_handler = removeTemporariesAndDie;
            sigemptyset(&action.sa_mask);
            ::sigaction(sig, &action, nullptr);
        }
        return true;
    }();
    (void)installed;
}

/// Registers @p path for removal on interruption; returns its slot (-1 if all are taken).
int registerTemporary(const std::string& path)
{
    installInterruptCleanup();
    char* copy = ::strdup(path.c_str());
    if (!copy) return -1;
    for (int i = 0; i < kTemporarySlots; ++i) {
        char* expected = nullptr;
        if (gTemporaries[i].compare_exchange_strong(expected, copy)) return i;
    }
    std::free(copy);
    return -1;
}

void unregisterTemporary(int slot)
{
    if (slot >= 0) std::free(gTemporaries[slot].exchange(nullptr));
}

} // namespace

AtomicFile::AtomicFile(const std::string& target) : mTarget(target)
{
    checkTarget(target);

    // A per-process counter keeps temporary names unique when several outputs are written
    // to the same folder at once; O_EXCL guarantees we never clobber someone else's file.
    static std::atomic<unsigned> counter{0};
    const fs::path folder = folderOf(target);
    const std::string name = fs::path(target).filename().string();
    int fd = -1;
    for (int attempt = 0; attempt < 100 && fd < 0; ++attempt) {
        mTemp = (folder / ("." + name + ".tmp-" + std::to_string(::getpid()) + "-" +
                           std::to_string(counter.fetch_add(1))))
                    .string();
        fd = ::open(mTemp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (fd < 0 && errno != EEXIST) break;
    }
    if (fd < 0) {
        const int code = errno;
        mTemp.clear();
        throwWriteError(target, errnoText(code));
    }
    mFile = ::fdopen(fd, "wb");
    if (!mFile) {
        const int code = errno;
        ::close(fd);
        ::unlink(mTemp.c_str());
        mTemp.clear();
        throwWriteError(target, errnoText(code));
    }
    mSlot = registerTemporary(mTemp);
}

AtomicFile::~AtomicFile()
{
    if (mFile) std::fclose(mFile);
    if (!mCommitted && !mTemp.empty()) ::unlink(mTemp.c_str());
    unregisterTemporary(mSlot);
}

void AtomicFile::write(const void* data, std::size_t bytes)
{
    if (!mFile) throwWriteError(mTarget, "the file is already closed");
    if (bytes == 0) return;
    errno = 0;
    if (std::fwrite(data, 1, bytes, mFile) != bytes) {
        const int code = errno != 0 ? errno : EIO;
        throwWriteError(mTarget, errnoText(code));
    }
}

void AtomicFile::writeAt(std::uint64_t offset, const void* data, std::size_t bytes)
{
    if (!mFile) throwWriteError(mTarget, "the file is already closed");
    if (std::fflush(mFile) != 0) throwWriteError(mTarget, errnoText(errno != 0 ? errno : EIO));
    const int fd = ::fileno(mFile);
    const char* p = static_cast<const char*>(data);
    while (bytes > 0) {
        const ssize_t done = ::pwrite(fd, p, bytes, off_t(offset));
        if (done < 0 && errno == EINTR) continue;
        if (done <= 0) throwWriteError(mTarget, errnoText(done < 0 ? errno : EIO));
        p += done, offset += std::uint64_t(done), bytes -= std::size_t(done);
    }
}

void AtomicFile::commit()
{
    if (mCommitted) return;
    if (!mFile) throwWriteError(mTarget, "the file is already closed");
    // Durability against power loss (fsync) is not attempted: the goal is that readers and
    // interrupted runs never see a half-written file, which rename() alone guarantees.
    errno = 0;
    const bool flushed = std::fflush(mFile) == 0 && !std::ferror(mFile);
    const int flushErrno = errno;
    const bool closed = std::fclose(mFile) == 0;
    const int closeErrno = errno;
    mFile = nullptr;
    if (!flushed) throwWriteError(mTarget, errnoText(flushErrno != 0 ? flushErrno : EIO));
    if (!closed) throwWriteError(mTarget, errnoText(closeErrno));
    if (std::rename(mTemp.c_str(), mTarget.c_str()) != 0) throwWriteError(mTarget, errnoText(errno));
    mCommitted = true;
    unregisterTemporary(mSlot);
    mSlot = -1;
}

void checkWritable(const std::string& target)
{
    checkTarget(target);
    const fs::path folder = folderOf(target);
    if (::access(folder.c_str(), W_OK) != 0)
        throwWriteError(target, "the folder '" + folder.string() + "' is not writable (" +
                                    errnoText(errno) + ")");
}

void writeTextFileAtomic(const std::string& target, const std::string& text)
{
    AtomicFile file(target);
    file.write(text);
    file.commit();
}

} // namespace msii
