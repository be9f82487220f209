#pragma once
// Test support: runs a program of the project (msii, msii-samples) as users do, through the
// shell, and captures its exit status, standard output and standard error.
#include "files.h"

#include <cstdlib>
#include <filesystem>
#include <string>

#include <sys/wait.h>
#include <unistd.h>

namespace msii::test {

struct RunResult {
    int code = -1;  ///< exit status; -1 if the program did not exit normally
    std::string out, err;
};

/// @p path in single quotes, for an argument list as written in a shell.
inline std::string quoted(const std::filesystem::path& path)
{
    return "'" + path.string() + "'";
}

/// Runs `'program' args` (args as written in a shell), with its output captured in files of
/// @p folder that are removed afterwards (names unique per process and call, so tests may run
/// in parallel).
inline RunResult runProgram(const std::string& program, const std::string& args, const std::filesystem::path& folder)
{
    static int call = 0;
    const std::string stem = (folder / (".run-" + std::to_string(::getpid()) + "-" + std::to_string(++call))).string();
    const std::string out = stem + ".out", err = stem + ".err";
    const std::string command = "'" + program + "' " + args + " >'" + out + "' 2>'" + err + "'";
    const int status = std::system(command.c_str());
    RunResult r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = readFile(out);
    r.err = readFile(err);
    std::filesystem::remove(out);
    std::filesystem::remove(err);
    return r;
}

} // namespace msii::test
