#pragma once
/// @file terminal_progress.h
/// @brief The progress line on a terminal: a RunContext listener that redraws one line on
/// stderr ("V and S, level 1:  42.0 %  (3.1 s)"). Shown on a terminal, silent in scripts;
/// or, for a program that runs msii and shows the progress itself (the QGIS plugin), one
/// line per report: "msii: progress 42.0 V and S, level 1".

#include <msii/core/run_context.h>

namespace msii {

/// True when stderr is a terminal (not a pipe, a file or a CI log).
bool stderrIsTerminal();

class TerminalProgress {
public:
    enum class Style {
        Off,    ///< nothing (--quiet, or stderr is not a terminal)
        Line,   ///< one line redrawn in place
        Lines,  ///< "msii: progress PERCENT STAGE", a line per report (at most ~10 per second), for programs
    };
    /// @param enabled  false: draw nothing (e.g. --quiet, or stderr is not a terminal).
    explicit TerminalProgress(bool enabled = stderrIsTerminal()) : mStyle(enabled ? Style::Line : Style::Off) {}
    explicit TerminalProgress(Style style) : mStyle(style) {}
    /// Ends an unfinished line (work that stopped with an error), so that the error starts
    /// a line of its own.
    ~TerminalProgress();

    /// The listener to give a RunContext.
    RunContext::Listener listener();
    bool enabled() const { return mStyle != Style::Off; }

private:
    void draw(const ProgressUpdate& update);
    Style mStyle;
    bool mLineOpen = false;
};

} // namespace msii
