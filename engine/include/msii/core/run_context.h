#pragma once
/// @file run_context.h
/// @brief What a caller hands a long computation besides its inputs: a way to follow it
/// (progress) and to stop it (cancellation), in the shape of OpenVDB's interrupter
/// (start / advance / end, wasInterrupted). Engine functions take a `RunContext*` that may
/// be null. The terminal's progress line (core/terminal_progress.h) and the Python module's
/// `progress=` callable are listeners of it.

#include <atomic>
#include <chrono>
#include <exception>
#include <functional>
#include <mutex>
#include <string>

namespace msii {

/// Thrown out of the engine function whose RunContext was cancelled (cancel()).
struct Cancelled : std::exception {
    const char* what() const noexcept override { return "the computation was cancelled"; }
};

/// One report to a listener.
struct ProgressUpdate {
    const std::string& stage;  ///< e.g. "V and S, level 1", with the prefix (setPrefix)
    std::size_t done = 0, total = 0;
    double seconds = 0;        ///< since the stage started
    bool finished = false;     ///< the stage's last report (end())
};

class RunContext {
public:
    /// Called at start(), from advance() at most ~10 times per second (any thread, one at
    /// a time) and at end(). It may throw to cancel the work: the exception leaves advance()
    /// and the engine function that called it (TBB cancels the other tasks of a parallel
    /// loop).
    using Listener = std::function<void(const ProgressUpdate&)>;

    RunContext() = default;
    explicit RunContext(Listener listener) : mListener(std::move(listener)) {}

    /// Engine side: a stage of @p total units begins, @p done units are done (thread-safe;
    /// throws Cancelled once cancel() was called), the stage ends.
    void start(const std::string& stage, std::size_t total);
    void advance(std::size_t done = 1);
    void end();
    /// Text put before every stage from now on, e.g. "tile 3 of 25: " (empty: none).
    void setPrefix(const std::string& prefix);

    void setListener(Listener listener);

    /// Caller side, from any thread: stop the work at the next advance() (or
    /// throwIfCancelled()), which throws Cancelled.
    void cancel() { mCancelled = true; }
    bool wasInterrupted() const { return mCancelled.load(std::memory_order_relaxed); }
    void throwIfCancelled() const
    {
        if (wasInterrupted()) throw Cancelled{};
    }

private:
    std::string mStage, mPrefix;
    std::size_t mTotal = 0;
    std::atomic<std::size_t> mDone{0};
    std::atomic<bool> mCancelled{false};
    std::mutex mMutex;
    std::chrono::steady_clock::time_point mStart, mLastReport;
    bool mActive = false;
    std::atomic<bool> mHalfwayReported{false};  ///< a stage reports once past half its work, however fast
    Listener mListener;
};

} // namespace msii
