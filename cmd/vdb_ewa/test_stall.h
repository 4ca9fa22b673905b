/// @file test_stall.h
/// @brief Fault injection for the signal tests (tests/batch_test.cpp): with
///        VDB_EWA_TEST_STALL=read in the environment, the CLI blocks for a minute where it
///        starts reading a grid, without checking for a stop, as a read from a hung network
///        file would. A stop signal must still end it within 0.5 s (the watchdog).
///        VDB_EWA_TEST_STALL=between-frames holds a sequence after each written frame until a
///        stop arrives, so the test can stop it where no frame is in flight.
#pragma once

#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <ctime>

namespace vdb_ewa::cli {

/// Block at @a stage for a minute, or until @a until() is true (checked every 10 ms) if given.
inline void stallForTests(const char* stage, bool (*until)() = nullptr)
{
    const char* wanted = std::getenv("VDB_EWA_TEST_STALL");
    if (!wanted || std::strcmp(wanted, stage) != 0) return;
    static const char line[] = "vdb_ewa: VDB_EWA_TEST_STALL: stalling\n";
    [[maybe_unused]] const ssize_t n = ::write(STDERR_FILENO, line, sizeof line - 1);
    for (int ms = 0; ms < 60000 && !(until && until()); ms += 10) {
        timespec tick{0, 10000000L};
        while (nanosleep(&tick, &tick) != 0) {
        }
    }
}

} // namespace vdb_ewa::cli
