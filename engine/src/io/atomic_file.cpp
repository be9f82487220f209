#include <msii/io/atomic_file.h>

#include <msii/core/errors.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <condition_variable>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <system_error>
#include <thread>
#include <vector>

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

/// Writes all of @p bytes at @p offset; 0 or the errno of the failure.
int pwriteAll(int fd, const char* data, std::size_t bytes, std::uint64_t offset)
{
    while (bytes > 0) {
        const ssize_t done = ::pwrite(fd, data, bytes, off_t(offset));
        if (done < 0 && errno == EINTR) continue;
        if (done <= 0) return done < 0 ? errno : EIO;
        data += done, offset += std::uint64_t(done), bytes -= std::size_t(done);
    }
    return 0;
}

} // namespace

// ---------------------------------------------------------------------------------------
// AtomicFile::Mode::Large: appended bytes fill one of two aligned blocks; a full block is
// handed to a background thread that writes it with O_DIRECT while the other one fills.

class DirectWriter {
public:
    static constexpr std::size_t kAlign = 4096;                   // offsets, sizes, addresses
    static constexpr std::size_t kBlock = std::size_t(16) << 20;  // bytes per write

    /// A writer on a second descriptor of @p path opened with O_DIRECT; nullptr where the
    /// file system refuses it. Blocks whose direct write is refused all the same (EINVAL:
    /// alignment or file system) go through @p bufferedFd.
    static std::unique_ptr<DirectWriter> open(const std::string& path, int bufferedFd)
    {
#ifdef O_DIRECT
        const int fd = ::open(path.c_str(), O_WRONLY | O_DIRECT | O_CLOEXEC);
        if (fd < 0) return nullptr;
        std::unique_ptr<DirectWriter> writer(new DirectWriter(fd, bufferedFd));
        // The same file as the ordinary descriptor (not one put there since), and memory.
        struct stat a {}, b {};
        if (::fstat(fd, &a) != 0 || ::fstat(bufferedFd, &b) != 0 || a.st_dev != b.st_dev || a.st_ino != b.st_ino)
            return nullptr;
        if (!writer->mBuffer[0] || !writer->mBuffer[1]) return nullptr;
        try {
            writer->mThread = std::thread([w = writer.get()] { w->run(); });
        } catch (const std::system_error&) {
            return nullptr;  // no thread: buffered writes
        }
        return writer;
#else
        (void)path, (void)bufferedFd;
        return nullptr;
#endif
    }

    ~DirectWriter()
    {
        if (mThread.joinable()) {
            {
                std::lock_guard<std::mutex> lock(mMutex);
                mStop = true;
            }
            mWake.notify_all();
            mThread.join();
        }
        ::close(mFd);
        for (char* b : mBuffer) std::free(b);
    }

    /// Appends @p bytes; 0 or the errno of a failed write (this one's or an earlier block's).
    int append(const char* data, std::size_t bytes)
    {
        if (const int e = mError.load(std::memory_order_relaxed)) return e;
        while (bytes > 0) {
            const std::size_t n = std::min(bytes, kBlock - mFill);
            std::memcpy(mBuffer[mCurrent] + mFill, data, n);
            mFill += n, data += n, bytes -= n;
            if (mFill == kBlock)
                if (const int e = submit(kBlock)) return e;
        }
        return 0;
    }

    /// Writes @p bytes at @p offset: the part within the block being filled is changed in
    /// place, the rest goes through @p bufferedFd once no block is in flight (so that it
    /// lands after the blocks written before). 0 or an errno.
    int patch(int bufferedFd, std::uint64_t offset, const char* data, std::size_t bytes)
    {
        const std::uint64_t end = offset + bytes, lo = mOffset, hi = mOffset + mFill;
        if (offset < lo || end > hi)
            if (const int e = drain()) return e;
        if (offset < lo)
            if (const int e = pwriteAll(bufferedFd, data, std::size_t(std::min(end, lo) - offset), offset)) return e;
        if (offset < hi && end > lo) {
            const std::uint64_t from = std::max(offset, lo), to = std::min(end, hi);
            std::memcpy(mBuffer[mCurrent] + (from - lo), data + (from - offset), std::size_t(to - from));
        }
        if (end > hi) {
            const std::uint64_t from = std::max(offset, hi);
            if (const int e = pwriteAll(bufferedFd, data + (from - offset), std::size_t(end - from), from)) return e;
        }
        return 0;
    }

    /// Writes what is left: the block being filled up to its last whole 4 KB directly, the
    /// few bytes after that through @p bufferedFd. 0 or an errno.
    int finish(int bufferedFd)
    {
        const std::size_t aligned = mFill / kAlign * kAlign, rest = mFill - aligned;
        const std::vector<char> tail(mBuffer[mCurrent] + aligned, mBuffer[mCurrent] + mFill);
        const std::uint64_t tailOffset = mOffset + aligned;
        if (aligned > 0)
            if (const int e = submit(aligned)) return e;
        if (const int e = drain()) return e;
        return rest > 0 ? pwriteAll(bufferedFd, tail.data(), rest, tailOffset) : 0;
    }

private:
    DirectWriter(int fd, int bufferedFd) : mFd(fd), mBufferedFd(bufferedFd)
    {
        for (char*& b : mBuffer)
            if (::posix_memalign(reinterpret_cast<void**>(&b), kAlign, kBlock) != 0) b = nullptr;
    }

    /// Waits until no block is in flight; 0 or the first errno of the background writes.
    int drain()
    {
        std::unique_lock<std::mutex> lock(mMutex);
        mIdle.wait(lock, [&] { return !mPending; });
        return mError.load();
    }

    /// Hands the first @p bytes of the block being filled to the thread; fills the other.
    int submit(std::size_t bytes)
    {
        {
            std::unique_lock<std::mutex> lock(mMutex);
            mIdle.wait(lock, [&] { return !mPending; });
            if (const int e = mError.load()) return e;
            mPending = true;
            mPendingData = mBuffer[mCurrent];
            mPendingBytes = bytes;
            mPendingOffset = mOffset;
        }
        mWake.notify_one();
        mCurrent ^= 1;
        mOffset += bytes;
        mFill = 0;
        return 0;
    }

    void run()
    {
        std::unique_lock<std::mutex> lock(mMutex);
        while (true) {
            mWake.wait(lock, [&] { return mStop || mPending; });
            if (!mPending) return;  // stopped with nothing in flight
            const char* data = mPendingData;
            const std::size_t bytes = mPendingBytes;
            const std::uint64_t offset = mPendingOffset;
            lock.unlock();
            int e = pwriteAll(mFd, data, bytes, offset);
            if (e == EINVAL) e = pwriteAll(mBufferedFd, data, bytes, offset);
            lock.lock();
            if (e != 0 && mError.load() == 0) mError.store(e);
            mPending = false;
            mIdle.notify_all();
        }
    }

    int mFd, mBufferedFd;
    char* mBuffer[2] = {nullptr, nullptr};
    int mCurrent = 0;
    std::size_t mFill = 0;      // bytes in the block being filled
    std::uint64_t mOffset = 0;  // its offset in the file
    std::thread mThread;
    std::mutex mMutex;
    std::condition_variable mWake, mIdle;
    bool mPending = false, mStop = false;
    const char* mPendingData = nullptr;
    std::size_t mPendingBytes = 0;
    std::uint64_t mPendingOffset = 0;
    std::atomic<int> mError{0};  // the first errno of the background writes
};

namespace {

/// Removes the temporary files of @p name in @p folder that a killed run left (`kill -9`, a
/// machine that went down): names of msii's own pattern, .NAME.tmp-PID-N, for this very
/// output, whose process no longer runs. A running writer's file is kept, whoever runs it.
void removeStaleTemporaries(const fs::path& folder, const std::string& name)
{
    const std::string prefix = "." + name + ".tmp-";
    std::error_code ec;
    for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
        const std::string file = it->path().filename().string();
        if (file.compare(0, prefix.size(), prefix) != 0) continue;
        const std::string rest = file.substr(prefix.size());  // PID-N
        const std::size_t dash = rest.find('-');
        if (dash == 0 || dash == std::string::npos || dash + 1 == rest.size() ||
            rest.find_first_not_of("0123456789-") != std::string::npos || rest.find('-', dash + 1) != std::string::npos)
            continue;
        const long pid = std::strtol(rest.c_str(), nullptr, 10);
        if (pid <= 0 || pid == long(::getpid())) continue;
        if (::kill(pid_t(pid), 0) == 0 || errno != ESRCH) continue;  // running, or not ours to judge
        std::error_code ignored;
        fs::remove(it->path(), ignored);
    }
}

} // namespace

AtomicFile::AtomicFile(const std::string& target, Mode mode) : mTarget(target)
{
    checkTarget(target);
    removeStaleTemporaries(folderOf(target), fs::path(target).filename().string());

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
    if (mode == Mode::Large) mDirect = DirectWriter::open(mTemp, ::fileno(mFile));
}

AtomicFile::~AtomicFile()
{
    mDirect.reset();  // waits for a block in flight
    if (mFile) std::fclose(mFile);
    if (!mCommitted && !mTemp.empty()) ::unlink(mTemp.c_str());
    unregisterTemporary(mSlot);
}

void AtomicFile::write(const void* data, std::size_t bytes)
{
    if (!mFile) throwWriteError(mTarget, "the file is already closed");
    if (bytes == 0) return;
    if (mDirect) {
        if (const int e = mDirect->append(static_cast<const char*>(data), bytes)) throwWriteError(mTarget, errnoText(e));
        mPosition += bytes;
        return;
    }
    errno = 0;
    if (std::fwrite(data, 1, bytes, mFile) != bytes) {
        const int code = errno != 0 ? errno : EIO;
        throwWriteError(mTarget, errnoText(code));
    }
    mPosition += bytes;
}

void AtomicFile::writeAt(std::uint64_t offset, const void* data, std::size_t bytes)
{
    if (!mFile) throwWriteError(mTarget, "the file is already closed");
    if (std::fflush(mFile) != 0) throwWriteError(mTarget, errnoText(errno != 0 ? errno : EIO));
    const int fd = ::fileno(mFile);
    const char* p = static_cast<const char*>(data);
    const int e = mDirect ? mDirect->patch(fd, offset, p, bytes) : pwriteAll(fd, p, bytes, offset);
    if (e != 0) throwWriteError(mTarget, errnoText(e));
}

void AtomicFile::commit()
{
    if (mCommitted) return;
    if (!mFile) throwWriteError(mTarget, "the file is already closed");
    if (mDirect) {
        const int e = mDirect->finish(::fileno(mFile));
        mDirect.reset();
        if (e != 0) {
            // Closed, so that neither a retry nor more writes can commit what is there.
            std::fclose(mFile);
            mFile = nullptr;
            throwWriteError(mTarget, errnoText(e));
        }
    }
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
