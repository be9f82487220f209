#pragma once
/// @file atomic_file.h
/// @brief Output files appear whole or not at all: data goes to a temporary file in the
/// target's folder, which is renamed over the target on commit() and removed otherwise, also
/// when the process is interrupted (SIGINT, SIGTERM, SIGHUP, unless the program handles them).

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>

namespace msii {

class DirectWriter;

/// Outputs expected to reach this size use AtomicFile::Mode::Large (PLY results, EXR maps).
constexpr std::size_t kLargeFileBytes = std::size_t(64) << 20;

class AtomicFile {
public:
    enum class Mode {
        Buffered,  ///< through the C library and the page cache
        /// For files of many MB written front to back (EXR maps): write() bypasses the page
        /// cache (O_DIRECT) in aligned blocks of 16 MB, written by a background thread while
        /// the next one fills. Copying into the page cache is what limits buffered writes on
        /// virtual machines (235 MB/s against 1.3 GB/s direct on the 2-core test machine).
        /// Falls back to Buffered where the file system refuses it (e.g. tmpfs).
        Large
    };

    /// Opens "<dir>/.<name>.tmp-<pid>-<n>" for binary writing.
    /// @throw IOError if the folder is missing or not writable.
    explicit AtomicFile(const std::string& target, Mode mode = Mode::Buffered);
    ~AtomicFile();  ///< removes the temporary file unless committed
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    void write(const void* data, std::size_t bytes);  ///< @throw IOError (e.g. disk full)
    void write(const std::string& text) { write(text.data(), text.size()); }
    /// Writes at byte @p offset of the file (anywhere, also beyond its current end, leaving
    /// a hole), without moving the position of write(). For writers that fill a file in
    /// pieces (io/write_ply.h's PlyPieceWriter). @throw IOError
    void writeAt(std::uint64_t offset, const void* data, std::size_t bytes);
    /// Flushes, closes and renames onto the target. @throw IOError
    void commit();
    /// The temporary file, for writers that open it themselves (e.g. OpenEXR): write it
    /// there without calling write(), then commit() renames it onto the target.
    const std::string& temporaryPath() const { return mTemp; }
    /// Bytes written so far by write() (the position of the next one).
    std::uint64_t position() const { return mPosition; }
    /// Whether write() bypasses the page cache (Mode::Large where the file system allows).
    bool writesDirect() const { return mDirect != nullptr; }

private:
    std::string mTarget, mTemp;
    std::FILE* mFile = nullptr;
    std::unique_ptr<DirectWriter> mDirect;
    std::uint64_t mPosition = 0;
    bool mCommitted = false;
    int mSlot = -1;  ///< registration for removal on interruption
};

/// Checks up front that @p target can be created (folder exists and is writable; the
/// target, if it exists, is a regular file). @throw IOError with the reason.
void checkWritable(const std::string& target);

/// Writes @p text to @p target atomically.
void writeTextFileAtomic(const std::string& target, const std::string& text);

} // namespace msii
