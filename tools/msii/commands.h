#pragma once
// The subcommands of the msii program; each registers its options on a CLI11 app and runs.
#include <CLI/CLI.hpp>

#include <functional>

namespace msii::tools {

/// Adds `msii compute`; the returned function runs it (after parsing) and returns the exit code.
std::function<int()> addComputeCommand(CLI::App& app);

} // namespace msii::tools
