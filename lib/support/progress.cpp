/// @file progress.cpp
#include "support/progress.h"

#include <algorithm>
#include <cmath>

namespace vdb_ewa {
namespace detail {

void Progress::stage(double from, double to)
{
    check();
    mFrom = from;
    mTo = to;
    mUnits = 1;
    mDone.store(0, std::memory_order_relaxed);
}

void Progress::finish()
{
    if (!mInterrupter) return;
    std::lock_guard<std::mutex> lock(mReport);
    mLastPercent = 100;
    mInterrupter->wasInterrupted(100);
}

void Progress::advance(std::uint64_t units)
{
    if (!mInterrupter) return;
    check();
    const std::uint64_t done = mDone.fetch_add(units, std::memory_order_relaxed) + units;
    const std::int64_t now = std::chrono::duration_cast<std::chrono::nanoseconds>(
        std::chrono::steady_clock::now().time_since_epoch()).count();
    const std::int64_t last = mLastReportNs.load(std::memory_order_relaxed);
    if (now - last < std::chrono::nanoseconds(kReportInterval).count()) return;
    std::unique_lock<std::mutex> lock(mReport, std::try_to_lock);
    if (!lock.owns_lock()) return; // another thread is reporting
    mLastReportNs.store(now, std::memory_order_relaxed);
    const double fraction = std::min(1.0, double(done) / double(mUnits));
    const int percent = std::max(mLastPercent, int(std::floor(mFrom + (mTo - mFrom) * fraction)));
    mLastPercent = percent;
    if (mInterrupter->wasInterrupted(percent)) mInterrupter->cancel();
    check();
}

} // namespace detail
} // namespace vdb_ewa
