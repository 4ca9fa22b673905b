/// @file granted_resources.h
/// @brief The CPUs and memory a farm task was granted: Slurm's environment variables and the
///        control group's limits, which a process inside a task must honour itself (without
///        cgroup enforcement, nothing stops it using the whole node) (docs/farm.md).
#pragma once

#include <functional>
#include <string>

namespace vdb_ewa::cli {

/// What the scheduler or the container grants; 0 where nothing says.
struct GrantedResources
{
    int cpus = 0;              ///< CPUs (whole: a cgroup quota of 1.5 CPUs is 2)
    std::string cpusFrom;      ///< where that came from ("SLURM_CPUS_PER_TASK=4", "cgroup cpu.max")
    double memoryBytes = 0.0;  ///< bytes
    std::string memoryFrom;    ///< "SLURM_MEM_PER_NODE=4096", "cgroup memory.max"
};

/// Where grantedResources() reads: the environment and the control group files (replaced by tests).
struct ResourceSources
{
    std::function<const char*(const char*)> getenv; ///< null: the process's environment
    std::string cgroupRoot = "/sys/fs/cgroup";       ///< the cgroup file systems' mount point
    std::string procSelfCgroup = "/proc/self/cgroup"; ///< the process's cgroup paths
    std::function<int()> affinityCpus;               ///< null: sched_getaffinity's count
    std::function<int()> onlineCpus;                 ///< null: the CPUs online (sysconf)
};

/// The smallest grant of each kind among:
/// - CPUs: SLURM_CPUS_PER_TASK, else the first count of SLURM_JOB_CPUS_PER_NODE ("2(x3)" is 2);
///   the cgroup's CPU quota (v2 cpu.max, v1 cpu.cfs_quota_us / cpu.cfs_period_us), rounded up;
///   the CPUs the process may run on (its affinity: a cpuset, Slurm's usual binding) where
///   they are fewer than the CPUs online; at most 65536;
/// - memory: SLURM_MEM_PER_NODE, or SLURM_MEM_PER_CPU times Slurm's CPUs (in MB, Slurm's unit);
///   the cgroup's limit (v2 memory.max, v1 memory.limit_in_bytes; "max" and v1's 2^63 are none).
/// Malformed values are ignored (Slurm writes them; a task must not fail on them).
GrantedResources grantedResources(const ResourceSources& sources = {});

/// What `--threads` and `--max-memory` become under @a granted: 0 threads is the granted CPUs,
/// a budget of 0 is 3/4 of the granted memory (as it is 3/4 of the physical memory without a
/// grant), at least 64 MB; other values stay. @a text says what was taken, for the log ("1
/// thread (SLURM_CPUS_PER_TASK=1), a frame's memory budget 375 MB (3/4 of ...)"); empty where
/// nothing was.
struct GrantedSettings
{
    int threads = 0;
    double maxMemory = 0.0;
    std::string text;
};
GrantedSettings grantedSettings(int threads, double maxMemory, const GrantedResources& granted = grantedResources());

} // namespace vdb_ewa::cli
