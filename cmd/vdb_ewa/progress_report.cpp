/// @file progress_report.cpp
#include "progress_report.h"

#include <atomic>
#include <csignal>
#include <cstdio>
#include <unistd.h>

namespace vdb_ewa::cli {
namespace {

std::atomic<ProgressReport*> gReport{nullptr};
volatile std::sig_atomic_t gStop = 0;

extern "C" void onStopSignal(int signal)
{
    gStop = 1;
    if (ProgressReport* report = gReport.load()) report->cancel();
    std::signal(signal, SIG_DFL); // a second signal kills at once
}

} // namespace

ProgressReport::ProgressReport(int frameCount, Verbosity verbosity)
    : mFrames(frameCount > 0 ? frameCount : 1), mTerminal(isatty(STDOUT_FILENO) == 1), mVerbosity(verbosity)
{
}

ProgressReport::~ProgressReport()
{
    ProgressReport* self = this;
    gReport.compare_exchange_strong(self, nullptr);
}

bool ProgressReport::wasInterrupted(int percent)
{
    show((100 * mFrame + percent) / mFrames);
    return false;
}

void ProgressReport::finishJob()
{
    if (!cancelled()) show(100);
    if (mTerminal && mVerbosity != Verbosity::Quiet && mShown >= 0) std::printf("\n");
    std::fflush(stdout);
}

void ProgressReport::show(int overall)
{
    if (mVerbosity == Verbosity::Quiet) return;
    if (mTerminal) {
        if (overall == mShown) return;
        mShown = overall;
        const int width = 40, filled = overall * width / 100;
        std::printf("\r[%s%s] %3d%%", std::string(std::size_t(filled), '#').c_str(),
            std::string(std::size_t(width - filled), ' ').c_str(), overall);
        std::fflush(stdout);
        return;
    }
    // Lines for farm managers: every 5 %, and 100 % once.
    const int step = overall / 5 * 5;
    if (step <= mShown) return;
    mShown = step;
    std::printf("%d%% done\n", step);
    std::fflush(stdout);
}

void installStopHandlers(ProgressReport& report)
{
    gReport.store(&report);
    std::signal(SIGINT, onStopSignal);
    std::signal(SIGTERM, onStopSignal);
}

bool stopRequested() { return gStop != 0; }

} // namespace vdb_ewa::cli
