#include <msii/core/run_context.h>
#include <msii/core/terminal_progress.h>

#include <algorithm>
#include <cstdio>
#include <unistd.h>

namespace msii {

void RunContext::start(const std::string& stage, std::size_t total)
{
    throwIfCancelled();
    std::lock_guard<std::mutex> lock(mMutex);
    mStage = mPrefix + stage;
    mTotal = total;
    mDone = 0;
    mStart = mLastReport = std::chrono::steady_clock::now();
    mActive = true;
    mHalfwayReported = false;
    if (mListener) mListener(ProgressUpdate{mStage, 0, mTotal, 0.0, false});
}

void RunContext::advance(std::size_t done)
{
    throwIfCancelled();
    mDone += done;
    if (!mListener) return;
    const auto now = std::chrono::steady_clock::now();
    // At most ten reports a second, and one once past half the stage's work however fast it
    // runs, so that a program reading the lines sees progress between start and end.
    const std::size_t sofar = mDone.load();
    const bool halfway = mTotal > 1 && 2 * sofar >= mTotal && sofar < mTotal;
    std::unique_lock<std::mutex> lock(mMutex, std::defer_lock);
    if (halfway && !mHalfwayReported) lock.lock();
    else if (!lock.try_lock()) return;
    const bool firstHalfway = halfway && !mHalfwayReported;
    if (!firstHalfway && now - mLastReport < std::chrono::milliseconds(100)) return;
    if (halfway) mHalfwayReported = true;
    mLastReport = now;
    mListener(ProgressUpdate{mStage, std::min(mDone.load(), mTotal), mTotal,
                             std::chrono::duration<double>(now - mStart).count(), false});
}

void RunContext::end()
{
    std::lock_guard<std::mutex> lock(mMutex);
    if (!mActive) return;
    mActive = false;
    if (mListener)
        mListener(ProgressUpdate{mStage, mTotal, mTotal,
                                 std::chrono::duration<double>(std::chrono::steady_clock::now() - mStart).count(),
                                 true});
}

void RunContext::setListener(Listener listener)
{
    std::lock_guard<std::mutex> lock(mMutex);
    mListener = std::move(listener);
}

void RunContext::setPrefix(const std::string& prefix)
{
    std::lock_guard<std::mutex> lock(mMutex);
    mPrefix = prefix;
}

bool stderrIsTerminal() { return ::isatty(STDERR_FILENO) == 1; }

TerminalProgress::~TerminalProgress()
{
    if (mLineOpen) {
        std::fputc('\n', stderr);
        std::fflush(stderr);
    }
}

RunContext::Listener TerminalProgress::listener()
{
    return [this](const ProgressUpdate& update) { draw(update); };
}

void TerminalProgress::draw(const ProgressUpdate& u)
{
    if (mStyle == Style::Off) return;
    const double frac = u.total ? std::min(1.0, double(u.done) / double(u.total)) : 1.0;
    if (mStyle == Style::Lines) {
        std::fprintf(stderr, "msii: progress %.1f %s\n", u.finished ? 100.0 : 100.0 * frac, u.stage.c_str());
        std::fflush(stderr);
        return;
    }
    if (u.finished)
        std::fprintf(stderr, "\r\033[K%s: done in %.2f s\n", u.stage.c_str(), u.seconds);
    else if (u.done == 0 && u.seconds == 0)
        std::fprintf(stderr, "\r\033[K%s ...", u.stage.c_str());
    else
        std::fprintf(stderr, "\r\033[K%s: %5.1f %%  (%.1f s)", u.stage.c_str(), 100.0 * frac, u.seconds);
    mLineOpen = !u.finished;
    std::fflush(stderr);
}

} // namespace msii
