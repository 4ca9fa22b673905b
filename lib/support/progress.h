/// @file progress.h
/// @brief A render's progress across its stages, reported to the host's Interrupter
///        (throttled, serialised) and checked for cancellation by the worker threads.
#pragma once

#include <vdb_ewa/interrupter.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>

namespace vdb_ewa {
namespace detail {

/// The interrupter's start() and end() around a render, end() also when it throws (the
/// Renderer's frame, a Scene's progressive render).
class InterrupterBracket
{
public:
    InterrupterBracket(Interrupter* interrupter, const std::string& name) : mInterrupter(interrupter)
    {
        if (mInterrupter) mInterrupter->start(name.c_str());
    }
    ~InterrupterBracket()
    {
        if (mInterrupter) mInterrupter->end();
    }
    InterrupterBracket(const InterrupterBracket&) = delete;
    InterrupterBracket& operator=(const InterrupterBracket&) = delete;

private:
    Interrupter* mInterrupter;
};

class Progress
{
public:
    /// @a interrupter may be null: then advance() does nothing.
    explicit Progress(Interrupter* interrupter) : mInterrupter(interrupter) {}

    /// The next stage spans [@a from, @a to) percent of the render. Called between stages, on
    /// the render's calling thread; throws Cancelled if the render was cancelled.
    void stage(double from, double to);
    /// The current stage has @a units of work, none done yet (set by the stage before its
    /// parallel loop; a stage of several loops restarts its count, reported percents never fall).
    void setUnits(std::uint64_t units)
    {
        mUnits = units > 0 ? units : 1;
        mDone.store(0, std::memory_order_relaxed);
    }
    /// Report 100 % (the render is complete; a cancel now is ignored).
    void finish();

    /// @a units more of the current stage are done. Thread-safe; throws Cancelled once the
    /// render is cancelled. Reports to the interrupter at most every kReportInterval.
    void advance(std::uint64_t units = 1);

    /// Throws Cancelled if the render was cancelled (no report).
    void check() const
    {
        if (mInterrupter && mInterrupter->cancelled()) throw Cancelled();
    }

    /// The current stage's units, and how many of them are done (for tests: a stage that
    /// keeps its declared count ends with both equal).
    std::uint64_t units() const { return mUnits; }
    std::uint64_t unitsDone() const { return mDone.load(std::memory_order_relaxed); }

    static constexpr std::chrono::milliseconds kReportInterval{50};

private:
    Interrupter* mInterrupter;
    double mFrom = 0, mTo = 0;
    std::uint64_t mUnits = 1;
    std::atomic<std::uint64_t> mDone{0};
    std::atomic<std::int64_t> mLastReportNs{0};
    int mLastPercent = -1; // guarded by mReport
    std::mutex mReport;
};

/// advance() and setUnits() through an optional pointer (the stages accept null).
inline void advance(Progress* progress, std::uint64_t units = 1)
{
    if (progress) progress->advance(units);
}

inline void setUnits(Progress* progress, std::uint64_t units)
{
    if (progress) progress->setUnits(units);
}

} // namespace detail
} // namespace vdb_ewa
