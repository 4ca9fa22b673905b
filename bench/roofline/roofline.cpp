/// @file roofline.cpp
/// @brief The peak rate of this machine for the volume rasteriser's inner loop, with the data
///        in L1: footprint samples (exp(-r/2) and the spread into a slab's optical depth and
///        moments) and slab composites per second on one core, scalar (as the library is
///        compiled) and 8 floats a vector (AVX2 + FMA, where the CPU has them). bench/bench.py
///        roofline divides the rates achieved in real frames by these (docs/performance.md).
#include "footprint_kernels.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>

namespace {

/// Splats like a frame's: centres over the tile and around it, footprint standard deviations
/// of 1-3 pixels (the low-pass filter's 1 pixel and up), cut off at 3 sigma.
std::vector<roofline::Footprint> typicalSplats(std::size_t n)
{
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::vector<roofline::Footprint> splats(n);
    for (auto& s : splats) {
        const float sx = 1.0f + 2.0f * u(rng), sy = 1.0f + 2.0f * u(rng), rho = 0.6f * (u(rng) - 0.5f);
        // Q = Sigma^-1 for Sigma = [sx^2, rho sx sy; rho sx sy, sy^2].
        const float det = sx * sx * sy * sy * (1.0f - rho * rho);
        s.qa = sy * sy / det;
        s.qb = -rho * sx * sy / det;
        s.qc = sx * sx / det;
        s.cx = -4.0f + 24.0f * u(rng);
        s.cy = -4.0f + 24.0f * u(rng);
        s.cutoff = 9.0f;
        s.tau = 0.01f * u(rng);
        s.w1 = 0.5f * s.tau;
        s.w2 = 0.33f * s.tau;
    }
    return splats;
}

template <std::size_t (*Splat)(const std::vector<roofline::Footprint>&, roofline::Accumulators&)>
void footprintSamples(benchmark::State& state)
{
    const auto splats = typicalSplats(1024);
    roofline::Accumulators acc;
    std::memset(&acc, 0, sizeof(acc));
    std::size_t samples = 0;
    for (auto _ : state) {
        samples += Splat(splats, acc);
        benchmark::DoNotOptimize(acc.tau);
        benchmark::ClobberMemory();
    }
    state.SetItemsProcessed(std::int64_t(samples));
}

template <std::size_t (*Composite)(roofline::Accumulators&)>
void slabComposites(benchmark::State& state)
{
    roofline::Accumulators acc;
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::size_t pixels = 0;
    for (auto _ : state) {
        state.PauseTiming();
        for (int p = 0; p < roofline::kPixels; ++p) {
            acc.tau[p] = 0.2f * u(rng);
            acc.emission[p] = u(rng);
            acc.transmittance[p] = 1.0f;
            acc.colour[p] = 0.0f;
        }
        state.ResumeTiming();
        for (int slab = 0; slab < 64; ++slab) {
            pixels += Composite(acc);
            acc.tau[slab] = 0.1f; // a slab with something in it
        }
        benchmark::DoNotOptimize(acc.colour);
        benchmark::ClobberMemory();
    }
    state.SetItemsProcessed(std::int64_t(pixels));
}

} // namespace

/// The vector kernels must do the scalar ones' work for their rate to mean anything: the same
/// samples, and accumulators within 1e-4 (exp per lane against forward differencing).
template <std::size_t (*Splat)(const std::vector<roofline::Footprint>&, roofline::Accumulators&),
          std::size_t (*Composite)(roofline::Accumulators&)>
bool vectorKernelsAgree()
{
    const auto splats = typicalSplats(256);
    roofline::Accumulators a, b;
    std::memset(&a, 0, sizeof(a));
    std::memset(&b, 0, sizeof(b));
    if (roofline::splatScalar(splats, a) != Splat(splats, b)) return false;
    for (int p = 0; p < roofline::kPixels; ++p) {
        a.emission[p] = b.emission[p] = 0.5f;
        a.transmittance[p] = b.transmittance[p] = 1.0f;
        const float* x[] = {a.tau, a.m1, a.m2};
        const float* y[] = {b.tau, b.m1, b.m2};
        for (int k = 0; k < 3; ++k) {
            if (!(std::abs(x[k][p] - y[k][p]) <= 1e-4f * std::max(1e-3f, std::abs(x[k][p])))) return false;
        }
    }
    roofline::compositeScalar(a);
    Composite(b);
    for (int p = 0; p < roofline::kPixels; ++p) {
        if (!(std::abs(a.colour[p] - b.colour[p]) <= 1e-5f && std::abs(a.transmittance[p] - b.transmittance[p]) <= 1e-5f)) return false;
    }
    return true;
}

int main(int argc, char** argv)
{
    benchmark::RegisterBenchmark("footprint_samples/scalar", footprintSamples<roofline::splatScalar>);
    benchmark::RegisterBenchmark("slab_composites/scalar", slabComposites<roofline::compositeScalar>);
    if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) {
        if (!vectorKernelsAgree<roofline::splatAvx2, roofline::compositeAvx2>()) {
            std::fprintf(stderr, "vdb_ewa_roofline: the AVX2 kernels disagree with the scalar ones\n");
            return 1;
        }
        benchmark::RegisterBenchmark("footprint_samples/avx2", footprintSamples<roofline::splatAvx2>);
        benchmark::RegisterBenchmark("slab_composites/avx2", slabComposites<roofline::compositeAvx2>);
    }
    // Highway picks its target itself (HWY_DYNAMIC_DISPATCH); the name says which.
    if (!vectorKernelsAgree<roofline::splatHwy, roofline::compositeHwy>()) {
        std::fprintf(stderr, "vdb_ewa_roofline: the Highway kernels (%s) disagree with the scalar ones\n",
                     roofline::hwyTarget());
        return 1;
    }
    const std::string hwy = std::string("/hwy_") + roofline::hwyTarget();
    benchmark::RegisterBenchmark(("footprint_samples" + hwy).c_str(), footprintSamples<roofline::splatHwy>);
    benchmark::RegisterBenchmark(("slab_composites" + hwy).c_str(), slabComposites<roofline::compositeHwy>);
    benchmark::Initialize(&argc, argv);
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
