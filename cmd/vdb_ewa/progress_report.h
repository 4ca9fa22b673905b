/// @file progress_report.h
/// @brief The CLI's side of a render's progress: `NN% done` lines on stdout for farm
///        managers, a bar on a terminal, and a clean stop on SIGINT / SIGTERM.
#pragma once

#include <vdb_ewa/interrupter.h>

#include <cstdio>
#include <string>

namespace vdb_ewa::cli {

/// Verbosity levels: -q, default, -v, -vv.
enum class Verbosity { Quiet = 0, Normal = 1, Verbose = 2, Debug = 3 };

/// Reports the progress of a job of @a frameCount frames as one overall percentage that only
/// rises, with the time left and the peak memory: lines `NN% done (ETA 0:12, peak 230 MB)`
/// (every 5 %) when stdout is not a terminal, an updating bar on its own line when it is. The
/// command's other stdout lines go through line(), so they never share the bar's line. Quiet
/// prints nothing. SIGINT and SIGTERM cancel it (see installStopHandlers).
class ProgressReport : public Interrupter
{
public:
    ProgressReport(int frameCount, Verbosity verbosity);
    ~ProgressReport() override;

    /// The next frame (0-based) begins.
    void beginFrame(int index) { mFrame = index; }
    /// @a count frames are written so far (for the line a stop signal prints); no frame is in
    /// flight until the next frameInFlight().
    void framesWritten(int count);
    /// A sequence's frame @a label is under way: a stop before frameEnded() or framesWritten()
    /// reports it (`frame N interrupted`), from reportInterruptedFrame() or, if the frame does
    /// not stop in time, from the watchdog. Exactly one of the two writes the line.
    void frameInFlight(int label);
    /// The frame in flight ended without being written (skipped or failed).
    void frameEnded();
    /// After a stop: `vdb_ewa: frame N interrupted` on stderr for the frame still in flight, if
    /// any (none when the stop came after the last frame was written).
    void reportInterruptedFrame();
    /// 100 % after the last frame (unless cancelled); ends a terminal bar's line.
    void finishJob();
    /// Print @a text and a newline on @a stream (stdout or stderr) on a line of its own: a
    /// terminal bar is cleared first and drawn again after it.
    void line(const std::string& text, std::FILE* stream = stdout);

    bool wasInterrupted(int percent) override;

private:
    void show(int overall);
    /// ", ETA 0:12, peak 230 MB" at @a overall percent (no ETA before 1 % or in the first second).
    std::string details(int overall) const;
    void drawBar() const;

    int mFrames;
    int mFrame = 0;
    int mShown = -1;
    bool mTerminal;
    bool mBarShown = false; ///< a terminal bar is on the current line
    Verbosity mVerbosity;
    double mStart; ///< seconds (steady clock) when the job began
};

/// The process's peak resident memory (vdb_ewa::peakResidentBytes: since it started, or since
/// resetPeakMemory()), in MB.
double peakMegabytes();

/// Start a new peak (a frame's): reset the kernel's high-water mark of resident memory.
/// @return false where it cannot (not Linux, no /proc): then the peaks are the process's.
bool resetPeakMemory();

/// "@a count @a noun" with an English plural: "1 frame", "2 frames".
std::string counted(long long count, const std::string& noun);

/// A stop signal ends the process this long after it arrived at the latest, plus the kernel's
/// time to end the threads (up to 0.13 s measured, where a thread was unmapping a frame's
/// arrays): four times the render's cancel checks (50 ms), within 0.5 s with a margin.
constexpr long kStopGraceMs = 200;

/// SIGINT and SIGTERM cancel @a report (an atomic store) and set stopRequested(); a frame
/// still running kStopGraceMs later (reading and writing do not check the cancel) is ended by
/// a watchdog thread, and so is everything at a second signal: the temporary outputs are
/// removed (removeTemporaryOutputs) and the process exits 130.
void installStopHandlers(ProgressReport& report);

/// True once SIGINT or SIGTERM arrived.
bool stopRequested();

} // namespace vdb_ewa::cli
