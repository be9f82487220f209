/// @file benchmark.cpp
/// @brief The helpers the cases of `msii-benchmark` share: medians, numbers for the
/// programs' options, child processes with their peak memory, and the tables' rows.
#include "benchmark.h"

#include <msii/core/stopwatch.h>

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

ChildRun runChild(const std::vector<std::string>& args)
{
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ChildRun r;
    const Stopwatch wall;
    pid_t pid = 0;
    if (posix_spawn(&pid, argv[0], nullptr, nullptr, argv.data(), environ) != 0) return r;
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
