/// @file coarse_image.cpp
#include "coarse_image.h"

#include <algorithm>

namespace vdb_ewa {
namespace detail {

int coarseScale(const Camera& camera)
{
    return std::clamp(std::min(camera.width(), camera.height()) / kCoarseSide, 1, kCoarseScale);
}

RenderSettings coarseSettings(const RenderSettings& asked)
{
    const RenderSettings draft = RenderSettings::preset(Quality::Draft);
    RenderSettings coarse = asked;
    coarse.splat = draft.splat;
    // Blocks merge only where their values are as smooth as the asked image wants: draft's
    // looser test lights merged blocks brighter, and more so at the coarse pixels (pyro at
    // 480x270: the coarse image's mean colour 18 % above the asked image's; 5 % so).
    coarse.splat.lodError = asked.splat.lodError;
    coarse.shadow.step = draft.shadow.step;
    coarse.shadow.resolution = draft.shadow.resolution;
    coarse.motionBlur.samples = draft.motionBlur.samples;
    coarse.motionBlur.layers = draft.motionBlur.layers;
    coarse.motionBlur.splitSigmas = draft.motionBlur.splitSigmas;
    coarse.motionBlur.lightFollows = draft.motionBlur.lightFollows;
    coarse.lensSamples = draft.lensSamples;
    return coarse;
}

bool coarseLightsAreAsked(const RenderSettings& asked)
{
    // What coarseSettings changes of what the light maps read (detail::lightKey): the step and
    // the spacing of their rays.
    const RenderSettings coarse = coarseSettings(asked);
    return coarse.shadow.step == asked.shadow.step && coarse.shadow.resolution == asked.shadow.resolution;
}

} // namespace detail
} // namespace vdb_ewa
