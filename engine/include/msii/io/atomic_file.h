#pragma once
/// @file atomic_file.h
/// @brief Output files appear whole or not at all: data goes to a temporary file in the
/// target's folder, which is renamed over the target on commit() and removed otherwise, also
/// when the process is interrupted (SIGINT, SIGTERM, SIGHUP, unless the program handles them).

#include <cstdint>
#include <cstdio>
#include <string>

namespace msii {

class AtomicFile {
public:
    /// Opens "<dir>/.<name>.tmp-<pid>-<n>" for binary writing.
    /// @throw IOError if the folder is missing or not writable.
    explicit AtomicFile(const std::string& target);
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

private:
    std::string mTarget, mTemp;
    std::FILE* mFile = nullptr;
    bool mCommitted = false;
    int mSlot = -1;  ///< registration for removal on interruption
};

/// Checks up front that @p target can be created (folder exists and is writable; the
/// target, if it exists, is a regular file). @throw IOError with the reason.
void checkWritable(const std::string& target);

/// Writes @p text to @p target atomically.
void writeTextFileAtomic(const std::string& target, const std::string& text);

} // namespace msii
