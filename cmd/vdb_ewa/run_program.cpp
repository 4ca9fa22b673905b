/// @file run_program.cpp
#include "run_program.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <sstream>

extern char** environ;

namespace vdb_ewa::cli {

ProgramResult runProgram(const std::string& program, const std::vector<std::string>& args, double timeoutSeconds)
{
    ProgramResult result;
    int outPipe[2], errPipe[2];
    if (::pipe2(outPipe, O_CLOEXEC) != 0) {
        result.failure = std::strerror(errno);
        return result;
    }
    if (::pipe2(errPipe, O_CLOEXEC) != 0) {
        result.failure = std::strerror(errno);
        ::close(outPipe[0]);
        ::close(outPipe[1]);
        return result;
    }
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_adddup2(&actions, outPipe[1], 1);
    posix_spawn_file_actions_adddup2(&actions, errPipe[1], 2);
    posix_spawnattr_t attributes;
    posix_spawnattr_init(&attributes);
    posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETPGROUP); // its own group, to kill a wrapper's children too
    posix_spawnattr_setpgroup(&attributes, 0);
    std::vector<char*> argv{const_cast<char*>(program.c_str())};
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    pid_t pid = 0;
    const int spawned = ::posix_spawnp(&pid, program.c_str(), &actions, &attributes, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    posix_spawnattr_destroy(&attributes);
    ::close(outPipe[1]);
    ::close(errPipe[1]);
    if (spawned != 0) {
        result.failure = spawned == ENOENT ? "not found" : std::strerror(spawned);
        ::close(outPipe[0]);
        ::close(errPipe[0]);
        return result;
    }
    // Read both streams until they close (a full pipe would block the program), or time out.
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeoutSeconds);
    pollfd fds[2] = {{outPipe[0], POLLIN, 0}, {errPipe[0], POLLIN, 0}};
    std::string* texts[2] = {&result.out, &result.err};
    bool timedOut = false;
    int openStreams = 2;
    while (openStreams > 0) {
        const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now()).count();
        if (left <= 0) {
            timedOut = true;
            break;
        }
        if (::poll(fds, 2, int(left)) < 0 && errno != EINTR) {
            result.failure = std::string("poll: ") + std::strerror(errno);
            break;
        }
        for (int i = 0; i < 2; ++i) {
            if (fds[i].fd < 0 || !(fds[i].revents & (POLLIN | POLLHUP | POLLERR))) continue;
            char buffer[4096];
            const ssize_t n = ::read(fds[i].fd, buffer, sizeof buffer);
            if (n > 0 && texts[i]->size() < (1u << 20)) texts[i]->append(buffer, std::size_t(n));
            if (n == 0 || (n < 0 && errno != EINTR && errno != EAGAIN)) {
                ::close(fds[i].fd);
                fds[i].fd = -1;
                --openStreams;
            }
        }
    }
    if (openStreams > 0) ::kill(-pid, SIGKILL); // timed out or cannot read: nothing may be left running
    for (const pollfd& f : fds) {
        if (f.fd >= 0) ::close(f.fd);
    }
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    if (timedOut) result.failure = "timed out after " + std::to_string(int(timeoutSeconds)) + " s";
    else if (!result.failure.empty()) result.exitCode = -1;
    else if (WIFEXITED(status)) result.exitCode = WEXITSTATUS(status);
    else if (WIFSIGNALED(status)) result.failure = "killed by signal " + std::to_string(WTERMSIG(status));
    return result;
}

std::string ProgramResult::why(const std::string& program) const
{
    if (!failure.empty()) return failure;
    std::string first, lastError;
    std::istringstream lines(err);
    for (std::string line; std::getline(lines, line);) {
        if (line.empty()) continue;
        if (first.empty()) first = line;
        if (line.find("error") != std::string::npos) lastError = line;
    }
    std::string text = !lastError.empty() ? lastError : !first.empty() ? first : "exit " + std::to_string(exitCode);
    const std::string name = program.substr(program.rfind('/') + 1) + ": ";
    if (text.rfind(name, 0) == 0) text.erase(0, name.size());
    return text;
}

} // namespace vdb_ewa::cli
