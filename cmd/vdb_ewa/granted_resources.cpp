/// @file granted_resources.cpp
#include "granted_resources.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <iomanip>
#include <sstream>
#include <vector>

#include <sched.h>
#include <unistd.h>

namespace vdb_ewa::cli {
namespace {

constexpr double kMB = 1024.0 * 1024.0;

/// A whole number at the start of @a text ("2(x3)" is 2), if it is positive.
std::optional<double> leadingCount(const char* text)
{
    if (!text || !*text) return std::nullopt;
    char* end = nullptr;
    const double v = std::strtod(text, &end);
    if (end == text || !std::isfinite(v) || v <= 0.0 || v != std::floor(v)) return std::nullopt;
    return v;
}

std::optional<std::string> firstLine(const std::string& path)
{
    std::ifstream in(path);
    std::string line;
    if (!in || !std::getline(in, line)) return std::nullopt;
    return line;
}

/// The folders holding controller @a controller's files for this process, the deepest first:
/// its cgroup and each parent (a parent's limit applies too), under cgroup v1's
/// <root>/<controller>/ or v2's <root>/ (and a hybrid's <root>/unified/).
std::vector<std::string> cgroupFolders(const ResourceSources& sources, const std::string& controller)
{
    std::vector<std::string> folders;
    std::ifstream in(sources.procSelfCgroup);
    std::string line;
    while (std::getline(in, line)) { // "hierarchy:controllers:path"
        const std::size_t a = line.find(':'), b = a == std::string::npos ? a : line.find(':', a + 1);
        if (b == std::string::npos) continue;
        const std::string controllers = line.substr(a + 1, b - a - 1);
        std::string path = line.substr(b + 1);
        std::vector<std::string> mounts;
        if (controllers.empty()) {
            mounts = {sources.cgroupRoot, sources.cgroupRoot + "/unified"};
        } else {
            std::stringstream list(controllers);
            bool listed = false;
            for (std::string c; std::getline(list, c, ',');) listed = listed || c == controller;
            if (!listed) continue;
            mounts = {sources.cgroupRoot + "/" + controller, sources.cgroupRoot + "/" + controllers};
        }
        for (;;) {
            for (const std::string& m : mounts) folders.push_back(m + (path == "/" ? "" : path));
            if (path.empty() || path == "/") break;
            const std::size_t slash = path.rfind('/');
            path = slash == 0 || slash == std::string::npos ? "/" : path.substr(0, slash);
        }
    }
    return folders;
}

/// The CPUs this process may run on (sched_getaffinity); 0 where unknown.
int affinityCount()
{
    cpu_set_t set;
    CPU_ZERO(&set);
    return ::sched_getaffinity(0, sizeof set, &set) == 0 ? CPU_COUNT(&set) : 0;
}

/// Keep the smaller of @a value and what @a grant holds.
void keepSmaller(double& grant, std::string& from, double value, const std::string& source)
{
    if (value > 0.0 && (grant == 0.0 || value < grant)) {
        grant = value;
        from = source;
    }
}

} // namespace

GrantedResources grantedResources(const ResourceSources& sources)
{
    const auto env = [&](const char* name) { return sources.getenv ? sources.getenv(name) : std::getenv(name); };
    const auto named = [&](const char* name) { return std::string(name) + "=" + env(name); };
    double cpus = 0.0, memory = 0.0;
    GrantedResources g;

    if (const auto perTask = leadingCount(env("SLURM_CPUS_PER_TASK"))) {
        keepSmaller(cpus, g.cpusFrom, *perTask, named("SLURM_CPUS_PER_TASK"));
    } else if (const auto perNode = leadingCount(env("SLURM_JOB_CPUS_PER_NODE"))) {
        keepSmaller(cpus, g.cpusFrom, *perNode, named("SLURM_JOB_CPUS_PER_NODE"));
    }
    const double slurmCpus = cpus; // SLURM_MEM_PER_CPU is per allocated CPU
    for (const std::string& folder : cgroupFolders(sources, "cpu")) {
        double quota = 0.0, period = 0.0;
        if (const auto max = firstLine(folder + "/cpu.max")) { // v2: "max 100000" or "150000 100000"
            std::istringstream(*max) >> quota >> period;
        } else if (const auto q = firstLine(folder + "/cpu.cfs_quota_us")) { // v1: -1 is none
            quota = std::atof(q->c_str());
            period = std::atof(firstLine(folder + "/cpu.cfs_period_us").value_or("0").c_str());
        }
        if (quota > 0.0 && period > 0.0) keepSmaller(cpus, g.cpusFrom, std::ceil(quota / period), "the cgroup's CPU quota (" + folder + ")");
    }
    const int affinity = sources.affinityCpus ? sources.affinityCpus() : affinityCount();
    const int online = sources.onlineCpus ? sources.onlineCpus() : int(::sysconf(_SC_NPROCESSORS_ONLN));
    if (affinity > 0 && affinity < online) keepSmaller(cpus, g.cpusFrom, affinity, "the process's CPU affinity (" + std::to_string(affinity) + " of " + std::to_string(online) + " CPUs)");
    cpus = std::min(cpus, 65536.0);

    if (const auto perNode = leadingCount(env("SLURM_MEM_PER_NODE"))) {
        keepSmaller(memory, g.memoryFrom, *perNode * kMB, named("SLURM_MEM_PER_NODE") + " MB");
    } else if (const auto perCpu = leadingCount(env("SLURM_MEM_PER_CPU"))) {
        const double n = slurmCpus > 0.0 ? slurmCpus : 1.0;
        keepSmaller(memory, g.memoryFrom, *perCpu * kMB * n, named("SLURM_MEM_PER_CPU") + " MB x " + std::to_string(int(n)) + " CPUs");
    }
    for (const std::string& folder : cgroupFolders(sources, "memory")) {
        std::optional<std::string> limit = firstLine(folder + "/memory.max"); // v2: "max" is none
        if (!limit) limit = firstLine(folder + "/memory.limit_in_bytes");     // v1: ~2^63 is none
        if (!limit) continue;
        const double bytes = std::atof(limit->c_str());
        if (bytes > 0.0 && bytes < 1.0e18) keepSmaller(memory, g.memoryFrom, bytes, "the cgroup's memory limit (" + folder + ")");
    }
    g.cpus = int(cpus);
    g.memoryBytes = memory;
    return g;
}

GrantedSettings grantedSettings(int threads, double maxMemory, const GrantedResources& granted)
{
    GrantedSettings s{threads, maxMemory, ""};
    std::ostringstream text;
    if (threads == 0 && granted.cpus > 0) {
        s.threads = granted.cpus;
        text << granted.cpus << (granted.cpus == 1 ? " thread (" : " threads (") << granted.cpusFrom << ")";
    }
    if (maxMemory == 0.0 && granted.memoryBytes > 0.0) {
        s.maxMemory = std::min(std::max(0.75 * granted.memoryBytes, 64.0 * kMB), 1.0e18); // --max-memory's range
        text << (text.tellp() > 0 ? ", " : "") << "a frame's memory budget " << std::fixed << std::setprecision(0) << s.maxMemory / kMB
             << " MB (3/4 of " << granted.memoryFrom << ")";
    }
    s.text = text.str();
    return s;
}

} // namespace vdb_ewa::cli
