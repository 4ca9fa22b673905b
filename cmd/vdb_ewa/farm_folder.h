/// @file farm_folder.h
/// @brief A job file's farm folder (`shot.farm/` beside `shot.json`): the submissions made by
///        `vdb_ewa submit` (<id>.sbatch, <id>.json) and their tasks' logs (logs/<id>_<task>.log),
///        and what those logs say of each frame (docs/farm.md).
#pragma once

#include <map>
#include <string>
#include <vector>

namespace vdb_ewa::cli {

/// The farm folder of the job file @a jobPath, absolute: @a given (--farm-dir) where it is not
/// empty, else `<the job's folder>/<its stem>.farm`.
std::string farmFolder(const std::string& jobPath, const std::string& given);

/// One `vdb_ewa submit`: the scheduler's job id, the frames it submitted (task t renders chunk t).
struct Submission
{
    std::string id;
    std::vector<int> frames;
    int chunk = 1;
    std::string submitted; ///< UTC, ISO 8601 (2026-11-26T17:40:00Z): sorts as it reads
    std::string folder;    ///< the tasks' working folder: the job's relative paths resolve there
    std::string options;   ///< submit's options but the frames', as words for a shell (a resubmission's)
};

/// The folder of the tasks' logs, and the log of task @a task of job @a id in it.
std::string taskLogFolder(const std::string& farm);
std::string taskLogPath(const std::string& farm, const std::string& id, int task);

/// Record @a s as <farm>/<id>.json (written whole: a temporary file renamed).
/// @throw IoError naming the file
void recordSubmission(const std::string& farm, const Submission& s);

/// The submissions recorded in @a farm, oldest first (by time, then job id); none where it does
/// not exist.
/// Records that cannot be read are skipped, each with a line in @a warnings.
std::vector<Submission> readSubmissions(const std::string& farm, std::vector<std::string>& warnings);

/// What a task's log says of a frame: its last line about it.
struct FrameEntry
{
    enum State { Done, Skipped, Failed, Interrupted } state = Done;
    std::string detail; ///< Failed: "exit 3: in.0003.vdb: no such file"
};

/// The render's line on @a frame, as readTaskLog reads it back: `vdb_ewa: frame 7 done: TEXT`,
/// `... skipped: TEXT`, `... failed (exit 3): TEXT`, `... interrupted` (@a text unused).
/// @a exitCode: Failed's.
std::string frameLogLine(int frame, FrameEntry::State state, const std::string& text, int exitCode = 0);

/// What a log says: each frame's last line (vdb_ewa's `frame N done|skipped|failed|interrupted`),
/// and why the scheduler ended the task, if it did (Slurm's `*** JOB 12 ON node CANCELLED AT
/// ... DUE TO PREEMPTION ***`: "cancelled due to preemption"; empty otherwise).
struct TaskLog
{
    std::map<int, FrameEntry> frames;
    std::string ended;
    bool exists = false; ///< the log exists: the task started
};

/// Read the log @a path (a missing file reads as empty).
TaskLog readTaskLog(const std::string& path);

} // namespace vdb_ewa::cli
