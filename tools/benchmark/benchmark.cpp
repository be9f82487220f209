/// @file benchmark.cpp
/// @brief The helpers the cases of `msii-benchmark` share: medians, numbers for the
/// programs' options, child processes with their peak memory, and the tables' rows.
#include "benchmark.h"

#include <fstream>

#include <msii/core/stopwatch.h>

#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

namespace msii::benchmark {

double median(std::vector<double> v)
{
    std::sort(v.begin(), v.end());
    return v.empty() ? 0 : (v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]));
}

std::string number(double v)
{
    char text[32];
    std::snprintf(text, sizeof(text), "%.6g", v);
    return std::string(text);
}

ChildRun runChild(const std::vector<std::string>& args, const std::string& log)
{
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ChildRun r;
    // With a log, the child's output goes there (programs that print a line per step).
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    if (!log.empty()) {
        posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
        posix_spawn_file_actions_adddup2(&actions, 1, 2);
    }
    const Stopwatch wall;
    pid_t pid = 0;
    const int spawned = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (spawned != 0) return r;
    int status = 0;
    rusage usage{};
    if (wait4(pid, &status, 0, &usage) != pid) return r;
    r.seconds = wall.seconds();
    r.peakBytes = double(usage.ru_maxrss) * 1024.0;
    r.ok = WIFEXITED(status) && WEXITSTATUS(status) == 0;
    return r;
}

void row(Report& report, const char* name, double value, const char* format)
{
    report.print("| %-62s | ", name);
    report.print(format, value);
    report.print(" |\n");
}

} // namespace msii::benchmark

namespace msii::benchmark {

std::size_t readVertexCount(const std::string& ply)
{
    std::ifstream in(ply, std::ios::binary);
    std::string line;
    while (std::getline(in, line) && line != "end_header")
        if (line.rfind("element vertex ", 0) == 0) return std::size_t(std::stoull(line.substr(15)));
    return 0;
}

} // namespace msii::benchmark
