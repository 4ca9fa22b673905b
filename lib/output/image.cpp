/// @file image.cpp
#include <vdb_ewa/image.h>

#include <algorithm>
#include <cmath>

namespace vdb_ewa {

bool Image::allFinite() const
{
    return std::all_of(rgba.begin(), rgba.end(), [](float v) { return std::isfinite(v); });
}

} // namespace vdb_ewa
