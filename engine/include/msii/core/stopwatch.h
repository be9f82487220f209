#pragma once
/// @file stopwatch.h
/// @brief Wall-clock seconds for the stage timings of the JSON sidecar and the benchmark.

#include <chrono>

namespace msii {

class Stopwatch {
public:
    /// Seconds since construction or the last restart().
    double seconds() const
    {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - mStart).count();
    }
    void restart() { mStart = std::chrono::steady_clock::now(); }

private:
    std::chrono::steady_clock::time_point mStart = std::chrono::steady_clock::now();
};

} // namespace msii
