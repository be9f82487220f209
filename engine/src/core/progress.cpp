#include <msii/core/progress.h>

#include <algorithm>
#include <cstdio>
#include <unistd.h>

namespace msii {

Progress::Progress(bool enabled) : mEnabled(enabled) {}

Progress::~Progress()
{
    // Not end(): its listener may throw, and a destructor runs during unwinding too.
    if (mActive && mEnabled) draw(true);
}

bool Progress::stderrIsTerminal() { return ::isatty(STDERR_FILENO) == 1; }

void Progress::start(const std::string& stage, std::size_t total)
{
    std::lock_guard<std::mutex> lock(mMutex);
    mStage = mPrefix + stage;
    mTotal = total;
    mDone = 0;
    mStart = mLastDraw = std::chrono::steady_clock::now();
    mActive = true;
    if (mEnabled) {
        std::fprintf(stderr, "\r\033[K%s ...", mStage.c_str());
        std::fflush(stderr);
    }
    if (mListener) mListener(mStage, 0, mTotal);
}

void Progress::advance(std::size_t done)
{
    mDone += done;
    if (!mEnabled && !mListener) return;
    const auto now = std::chrono::steady_clock::now();
    std::unique_lock<std::mutex> lock(mMutex, std::try_to_lock);
    if (!lock.owns_lock() || now - mLastDraw < std::chrono::milliseconds(100)) return;
    mLastDraw = now;
    if (mEnabled) draw(false);
    if (mListener) mListener(mStage, mDone.load(), mTotal);
}

void Progress::end()
{
    std::lock_guard<std::mutex> lock(mMutex);
    if (!mActive) return;
    mActive = false;
    if (mEnabled) draw(true);
    if (mListener) mListener(mStage, mTotal, mTotal);
}

void Progress::setListener(Listener listener)
{
    std::lock_guard<std::mutex> lock(mMutex);
    mListener = std::move(listener);
}

void Progress::setPrefix(const std::string& prefix)
{
    std::lock_guard<std::mutex> lock(mMutex);
    mPrefix = prefix;
}

void Progress::draw(bool final)
{
    const double secs =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - mStart).count();
    const double frac = mTotal ? std::min(1.0, double(mDone.load()) / double(mTotal)) : 1.0;
    if (final) {
        std::fprintf(stderr, "\r\033[K%s: done in %.2f s\n", mStage.c_str(), secs);
    } else {
        std::fprintf(stderr, "\r\033[K%s: %5.1f %%  (%.1f s)", mStage.c_str(), 100.0 * frac, secs);
    }
    std::fflush(stderr);
}

} // namespace msii
