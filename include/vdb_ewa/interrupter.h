/// @file interrupter.h
/// @brief Progress and cancellation of a render, in the spirit of
///        openvdb::util::NullInterrupter: a host derives from Interrupter and passes it to
///        Renderer::render / renderFrame.
#pragma once

#include <atomic>

#include "error.h"
#include "types.h"

namespace vdb_ewa {

/// Thrown by a render that was cancelled (Interrupter::cancel, or wasInterrupted returning
/// true). Nothing was written; the render's partial results are discarded.
class VDB_EWA_API Cancelled : public Error
{
public:
    Cancelled() : Error("render cancelled") {}
};

/// Receives a render's progress and may cancel it. The base class reports nothing and never
/// cancels unless cancel() is called.
///
/// Threading: start() and end() run on the thread that called render(). wasInterrupted() runs
/// on the render's worker threads, but never two calls at once, and at most about every
/// 50 ms. cancel() may be called from any thread at any time (it is an atomic store, safe in
/// a signal handler). After a cancel the render stops at its next check, within a small
/// fraction of a second, and throws Cancelled.
class VDB_EWA_API Interrupter
{
public:
    virtual ~Interrupter() = default;

    /// A render begins; @a name names what is rendered (the grid).
    virtual void start(const char* name) { (void)name; }
    /// The render finished, or stops because it was cancelled or failed.
    virtual void end() {}
    /// Progress of the current render in percent (0..100, rising). Return true to cancel.
    virtual bool wasInterrupted(int percent) { (void)percent; return false; }

    /// Request cancellation from any thread. Stays set until reset().
    void cancel() noexcept { mCancelled.store(true, std::memory_order_relaxed); }
    bool cancelled() const noexcept { return mCancelled.load(std::memory_order_relaxed); }
    /// Clear a cancellation so the interrupter can serve another render.
    void reset() noexcept { mCancelled.store(false, std::memory_order_relaxed); }

private:
    std::atomic<bool> mCancelled{false};
};

} // namespace vdb_ewa
