/// @file test_stall.h
/// @brief Fault injection for the signal tests (tests/batch_test.cpp): with
///        VDB_EWA_TEST_STALL=read in the environment, the CLI blocks for a minute where it
///        starts reading a grid, without checking for a stop, as a read from a hung network
///        file would. A stop signal must still end it within 0.5 s (the watchdog).
#pragma once

#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <ctime>

namespace vdb_ewa::cli {

inline void stallForTests(const char* stage)
{
    const char* wanted = std::getenv("VDB_EWA_TEST_STALL");
    if (!wanted || std::strcmp(wanted, stage) != 0) return;
    static const char line[] = "vdb_ewa: VDB_EWA_TEST_STALL: stalling\n";
    [[maybe_unused]] const ssize_t n = ::write(STDERR_FILENO, line, sizeof line - 1);
    timespec minute{60, 0};
    while (nanosleep(&minute, &minute) != 0) {
    }
}

} // namespace vdb_ewa::cli
