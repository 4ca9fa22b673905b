/// @file progress_report.cpp
#include "progress_report.h"

#include "exit_codes.h"

#include <vdb_ewa/output_file.h>
#include <vdb_ewa/renderer.h>

#include <fcntl.h>
#include <semaphore.h>
#include <sys/resource.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <limits>
#include <thread>

namespace vdb_ewa::cli {
namespace {

std::atomic<ProgressReport*> gReport{nullptr};
volatile std::sig_atomic_t gStop = 0;
sem_t gStopPosted; // the handler's post wakes the watchdog
std::atomic<int> gFramesWritten{0}, gFrames{1};
constexpr long long kNoFrame = std::numeric_limits<long long>::min();
std::atomic<long long> gFrameInFlight{kNoFrame}; ///< a sequence's frame label; taken by whoever reports it

/// Append the decimal digits of @a value (a sign if negative) at @a out. Async-signal-safe.
char* appendNumber(char* out, long long value)
{
    if (value < 0) *out++ = '-';
    unsigned long long magnitude = value < 0 ? 0ull - static_cast<unsigned long long>(value) : static_cast<unsigned long long>(value);
    char digits[24];
    int n = 0;
    do {
        digits[n++] = char('0' + magnitude % 10);
        magnitude /= 10;
    } while (magnitude > 0 && n < 24);
    while (n > 0) *out++ = digits[--n];
    return out;
}

/// The frame in flight's `vdb_ewa: frame N interrupted` line (the text of frameLogLine), once:
/// whoever takes the frame first writes it. Async-signal-safe.
void writeInterruptedFrame()
{
    const long long frame = gFrameInFlight.exchange(kNoFrame);
    if (frame == kNoFrame) return;
    char line[64] = "vdb_ewa: frame ";
    char* end = appendNumber(line + std::strlen(line), frame);
    static const char tail[] = " interrupted\n";
    std::memcpy(end, tail, sizeof tail - 1);
    end += sizeof tail - 1;
    [[maybe_unused]] const ssize_t n = ::write(STDERR_FILENO, line, std::size_t(end - line));
}

/// End the process now: no temporary output left, exit 130, the same line as a cooperative
/// stop ("interrupted: 3 of 10 frames written"). Async-signal-safe.
[[noreturn]] void stopNow()
{
    removeTemporaryOutputs();
    writeInterruptedFrame();
    char line[96] = "vdb_ewa: interrupted: ";
    char* end = line + std::strlen(line);
    end = appendNumber(end, gFramesWritten.load());
    std::memcpy(end, " of ", 4);
    end = appendNumber(end + 4, gFrames.load());
    static const char tail[] = " frames written\n", tailOne[] = " frame written\n";
    const bool one = gFrames.load() == 1;
    std::memcpy(end, one ? tailOne : tail, one ? sizeof tailOne - 1 : sizeof tail - 1);
    end += one ? sizeof tailOne - 1 : sizeof tail - 1;
    [[maybe_unused]] const ssize_t n = ::write(STDERR_FILENO, line, std::size_t(end - line));
    ::_exit(kExitInterrupted);
}

extern "C" void onStopSignal(int)
{
    if (gStop) stopNow(); // a second signal: at once
    gStop = 1;
    if (ProgressReport* report = gReport.load()) report->cancel();
    sem_post(&gStopPosted);
}

/// After a stop signal the render ends at its next check (every 50 ms at most), but reading a
/// grid (OpenVDB) and writing an image (OpenEXR) never check: a frame still running
/// kStopGraceMs after the signal is ended here, its temporary outputs removed.
void watchdog()
{
    while (sem_wait(&gStopPosted) != 0 && errno == EINTR) {
    }
    timespec grace{0, kStopGraceMs * 1000000L};
    while (nanosleep(&grace, &grace) != 0 && errno == EINTR) {
    }
    stopNow();
}

double nowSeconds()
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// 0:07, 1:05:03.
std::string clock(double seconds)
{
    const long s = std::lround(std::max(seconds, 0.0));
    char text[32];
    if (s >= 3600) std::snprintf(text, sizeof text, "%ld:%02ld:%02ld", s / 3600, s / 60 % 60, s % 60);
    else std::snprintf(text, sizeof text, "%ld:%02ld", s / 60, s % 60);
    return text;
}

} // namespace

double peakMegabytes()
{
    if (const std::uint64_t bytes = peakResidentBytes()) return double(bytes) / 1e6;
    rusage usage{}; // no /proc: the process's, with what the process that exec'd it held
    return getrusage(RUSAGE_SELF, &usage) == 0 ? double(usage.ru_maxrss) * 1024.0 / 1e6 : 0.0;
}

bool resetPeakMemory()
{
    // Writing 5 to clear_refs resets the high-water mark VmHWM (Linux 4.0, proc(5)).
    const int fd = ::open("/proc/self/clear_refs", O_WRONLY | O_CLOEXEC);
    if (fd < 0) return false;
    const bool reset = ::write(fd, "5", 1) == 1;
    ::close(fd);
    return reset;
}

std::string counted(long long count, const std::string& noun)
{
    return std::to_string(count) + " " + noun + (count == 1 ? "" : "s");
}

ProgressReport::ProgressReport(int frameCount, Verbosity verbosity)
    : mFrames(frameCount > 0 ? frameCount : 1), mTerminal(isatty(STDOUT_FILENO) == 1), mVerbosity(verbosity), mStart(nowSeconds())
{
    gFrames.store(mFrames);
    gFramesWritten.store(0);
}

void ProgressReport::framesWritten(int count)
{
    gFramesWritten.store(count);
    frameEnded();
}

void ProgressReport::frameInFlight(int label) { gFrameInFlight.store(label); }

void ProgressReport::frameEnded() { gFrameInFlight.store(kNoFrame); }

void ProgressReport::reportInterruptedFrame()
{
    if (mBarShown) {
        std::printf("\r\033[K");
        std::fflush(stdout);
        mBarShown = false;
    }
    writeInterruptedFrame();
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
    if (mBarShown) std::printf("\n");
    mBarShown = false;
    std::fflush(stdout);
}

void ProgressReport::line(const std::string& text, std::FILE* stream)
{
    if (mBarShown) {
        std::printf("\r\033[K");
        std::fflush(stdout);
    }
    std::fprintf(stream, "%s\n", text.c_str());
    std::fflush(stream);
    if (mBarShown) drawBar();
    std::fflush(stdout);
}

std::string ProgressReport::details(int overall) const
{
    const double elapsed = nowSeconds() - mStart;
    std::string out;
    if (overall >= 1 && overall < 100 && elapsed >= 1.0) out += "ETA " + clock(elapsed * double(100 - overall) / double(overall)) + ", ";
    char peak[48];
    std::snprintf(peak, sizeof peak, "peak %.0f MB", peakMegabytes());
    return out + peak;
}

void ProgressReport::drawBar() const
{
    const int width = 40, filled = mShown * width / 100;
    std::printf("\r[%s%s] %3d%%  %s\033[K", std::string(std::size_t(filled), '#').c_str(), std::string(std::size_t(width - filled), ' ').c_str(),
        mShown, details(mShown).c_str());
}

void ProgressReport::show(int overall)
{
    if (mVerbosity == Verbosity::Quiet) return;
    if (mTerminal) {
        // Redrawn at most once a percent (the ETA and peak change with it).
        if (overall <= mShown) return;
        mShown = overall;
        drawBar();
        mBarShown = true;
        std::fflush(stdout);
        return;
    }
    // Lines for farm managers: every 5 %, and 100 % once.
    const int step = overall / 5 * 5;
    if (step <= mShown) return;
    mShown = step;
    std::printf("%d%% done (%s)\n", step, details(step).c_str());
    std::fflush(stdout);
}

void installStopHandlers(ProgressReport& report)
{
    gReport.store(&report);
    static const bool started = [] {
        sem_init(&gStopPosted, 0, 0);
        std::thread(watchdog).detach();
        return true;
    }();
    (void)started;
    std::signal(SIGINT, onStopSignal);
    std::signal(SIGTERM, onStopSignal);
}

bool stopRequested() { return gStop != 0; }

} // namespace vdb_ewa::cli
