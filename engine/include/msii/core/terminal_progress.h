#pragma once
/// @file terminal_progress.h
/// @brief The progress line on a terminal: a RunContext listener that redraws one line on
/// stderr ("V and S, level 1:  42.0 %  (3.1 s)"). Shown on a terminal, silent in scripts.

#include <msii/core/run_context.h>

namespace msii {

/// True when stderr is a terminal (not a pipe, a file or a CI log).
bool stderrIsTerminal();

class TerminalProgress {
public:
    /// @param enabled  false: draw nothing (e.g. --quiet, or stderr is not a terminal).
    explicit TerminalProgress(bool enabled = stderrIsTerminal()) : mEnabled(enabled) {}
    /// Ends an unfinished line (work that stopped with an error), so that the error starts
    /// a line of its own.
    ~TerminalProgress();

    /// The listener to give a RunContext.
    RunContext::Listener listener();
    bool enabled() const { return mEnabled; }

private:
    void draw(const ProgressUpdate& update);
    bool mEnabled;
    bool mLineOpen = false;
};

} // namespace msii
