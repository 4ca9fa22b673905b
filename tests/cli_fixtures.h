/// @file cli_fixtures.h
/// @brief Running the `vdb_ewa` binary from tests: to completion, or in the background to
///        signal it.
#pragma once

#include "fixtures.h"

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fcntl.h>

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

extern char** environ;

namespace vdb_ewa::test {

struct CliRun
{
    int code = -1;
    std::string out, err;
};

inline std::string slurp(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

/// Run the CLI with @a args; $OCIO is unset unless @a ocio names a value for it. @a shellPrefix
/// goes before the command ("cd DIR && env A=1 ").
inline CliRun runCli(const TempDir& dir, const std::string& args, const std::string& ocio = "", const std::string& shellPrefix = "")
{
    const std::string out = dir.file("stdout.txt"), err = dir.file("stderr.txt");
    const std::string env = ocio.empty() ? "env -u OCIO " : "env OCIO='" + ocio + "' ";
    const int status = std::system((shellPrefix + env + VDB_EWA_CLI_PATH + " " + args + " >" + out + " 2>" + err).c_str());
    CliRun r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = slurp(out);
    r.err = slurp(err);
    return r;
}

/// The CLI running in the background (stdout and stderr to files), to signal and wait for.
class BackgroundCli
{
public:
    BackgroundCli(const TempDir& dir, const std::vector<std::string>& args)
        : mOut(dir.file("bg_stdout.txt")), mErr(dir.file("bg_stderr.txt"))
    {
        posix_spawn_file_actions_t actions;
        posix_spawn_file_actions_init(&actions);
        posix_spawn_file_actions_addopen(&actions, 1, mOut.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        posix_spawn_file_actions_addopen(&actions, 2, mErr.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        std::vector<std::string> all{VDB_EWA_CLI_PATH};
        all.insert(all.end(), args.begin(), args.end());
        std::vector<char*> argv;
        for (std::string& a : all) argv.push_back(a.data());
        argv.push_back(nullptr);
        if (posix_spawn(&mPid, VDB_EWA_CLI_PATH, &actions, nullptr, argv.data(), environ) != 0) mPid = -1;
        posix_spawn_file_actions_destroy(&actions);
    }
    ~BackgroundCli()
    {
        if (mPid > 0 && !mDone) {
            kill(mPid, SIGKILL);
            wait();
        }
    }

    bool started() const { return mPid > 0; }
    std::string out() const { return slurp(mOut); }
    std::string err() const { return slurp(mErr); }
    void signal(int sig) const { kill(mPid, sig); }

    /// Wait for the process; its exit code, or 128 + the signal that killed it.
    int wait()
    {
        int status = 0;
        waitpid(mPid, &status, 0);
        mDone = true;
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    }

private:
    std::string mOut, mErr;
    pid_t mPid = -1;
    bool mDone = false;
};

} // namespace vdb_ewa::test
