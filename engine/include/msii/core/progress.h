#pragma once
/// @file progress.h
/// @brief Progress reporting for long stages, in the shape of OpenVDB's interrupter
/// (start / advance / end). Shown on a terminal (stderr is a TTY), silent in scripts.

#include <atomic>
#include <chrono>
#include <functional>
#include <mutex>
#include <string>

namespace msii {

/// A thread-safe progress line on stderr. Engine functions take a `Progress*` that may be
/// null; they call start(), then advance() from any thread, then end().
class Progress {
public:
    /// @param enabled  false: never print. By default printing happens only when stderr is a
    ///                 terminal, so pipelines and CI logs stay clean.
    explicit Progress(bool enabled = stderrIsTerminal());
    ~Progress();

    void start(const std::string& stage, std::size_t total);
    /// Add @p done units of work (thread-safe); redraws at most ~10 times per second.
    void advance(std::size_t done = 1);
    void end();
    /// Text shown before every stage from now on, e.g. "tile 3 of 25: " (empty: none).
    void setPrefix(const std::string& prefix);

    /// Called with (stage, done, total) at start(), from advance() at most ~10 times per
    /// second (any thread, one at a time) and at end(), whether or not the line is printed:
    /// how programs (e.g. the Python module) follow the work. It may throw to cancel the
    /// work, as OpenVDB's interrupters do: the exception leaves advance() and the engine
    /// function that called it (TBB cancels the other tasks of a parallel loop).
    using Listener = std::function<void(const std::string& stage, std::size_t done, std::size_t total)>;
    void setListener(Listener listener);

    bool enabled() const { return mEnabled; }
    static bool stderrIsTerminal();

private:
    void draw(bool final);

    bool mEnabled;
    std::string mStage, mPrefix;
    std::size_t mTotal = 0;
    std::atomic<std::size_t> mDone{0};
    std::mutex mMutex;
    std::chrono::steady_clock::time_point mStart, mLastDraw;
    bool mActive = false;
    Listener mListener;
};

} // namespace msii
