/// @file color_management.cpp
/// @brief ColorConfig and ColorTransform over OpenColorIO 2.1 (docs/output.md#colour-management).
#include <vdb_ewa/color_management.h>

#include <vdb_ewa/error.h>

#include <OpenColorIO/OpenColorIO.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <map>
#include <sstream>

namespace OCIO = OCIO_NAMESPACE;

namespace vdb_ewa {
namespace detail {
extern const char* const kShippedOcioConfig; // generated from share/ocio/config.ocio
} // namespace detail

struct ColorConfig::Impl
{
    OCIO::ConstConfigRcPtr config;
    std::string origin;
};

struct ColorTransform::Impl
{
    OCIO::ConstCPUProcessorRcPtr cpu;
    bool noOp = true;
};

namespace {

std::string lower(std::string s)
{
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return s;
}

std::string joined(const std::vector<std::string>& names)
{
    std::string out;
    for (const std::string& n : names) out += (out.empty() ? "" : ", ") + ("'" + n + "'");
    return out;
}

/// validate() checks the config's structure; also build the scene_linear -> default display
/// and view processor, which reads the files (LUTs) that a working config needs.
OCIO::ConstConfigRcPtr validated(OCIO::ConstConfigRcPtr config)
{
    config->validate();
    const char* display = config->getDefaultDisplay();
    if (config->hasRole(OCIO::ROLE_SCENE_LINEAR) && display && *display) {
        OCIO::DisplayViewTransformRcPtr dvt = OCIO::DisplayViewTransform::Create();
        dvt->setSrc(OCIO::ROLE_SCENE_LINEAR);
        dvt->setDisplay(display);
        dvt->setView(config->getDefaultView(display));
        config->getProcessor(dvt)->getDefaultCPUProcessor();
    }
    return config;
}

} // namespace

ColorConfig ColorConfig::shipped()
{
    static const ColorConfig config = [] {
        auto impl = std::make_shared<Impl>();
        std::istringstream text(detail::kShippedOcioConfig);
        impl->config = validated(OCIO::Config::CreateFromStream(text));
        impl->origin = "vdb_ewa's shipped config";
        return ColorConfig(impl);
    }();
    return config;
}

ColorConfig ColorConfig::fromFile(const std::string& path)
{
    if (path.rfind("ocio://", 0) == 0) {
        throw IoError(path + ": built-in config URIs need OpenColorIO 2.2 or later (this build has " +
                      std::string(OCIO::GetVersion()) + ")");
    }
    try {
        auto impl = std::make_shared<Impl>();
        impl->config = validated(OCIO::Config::CreateFromFile(path.c_str()));
        impl->origin = path;
        return ColorConfig(impl);
    } catch (const OCIO::Exception& e) {
        std::string what = e.what();
        std::replace(what.begin(), what.end(), '\n', ' ');
        throw IoError(path + ": cannot use the OpenColorIO config (" + what + ")");
    }
}

ColorConfig ColorConfig::fromString(const std::string& text, const std::string& workingDir)
{
    try {
        std::istringstream stream(text);
        OCIO::ConfigRcPtr config = OCIO::Config::CreateFromStream(stream)->createEditableCopy();
        if (!workingDir.empty()) config->setWorkingDir(workingDir.c_str());
        auto impl = std::make_shared<Impl>();
        impl->config = validated(config);
        impl->origin = "a config given as text";
        return ColorConfig(impl);
    } catch (const OCIO::Exception& e) {
        throw ValueError(std::string("invalid OpenColorIO config text: ") + e.what());
    }
}

ColorConfig ColorConfig::resolve(const std::string& explicitPath, std::vector<std::string>& warnings)
{
    if (!explicitPath.empty()) {
        try {
            return fromFile(explicitPath);
        } catch (const Error& e) {
            warnings.push_back(std::string(e.what()) + "; trying $OCIO, then vdb_ewa's shipped config");
        }
    }
    const char* env = std::getenv("OCIO");
    if (env && *env) {
        try {
            return fromFile(env);
        } catch (const Error& e) {
            warnings.push_back(std::string("$OCIO: ") + e.what() + "; using vdb_ewa's shipped config");
        }
    }
    return shipped();
}

const std::string& ColorConfig::origin() const { return mImpl->origin; }

bool ColorConfig::isShipped() const { return mImpl == shipped().mImpl; }

std::string ColorConfig::roleSpace(const std::string& role) const
{
    if (!mImpl->config->hasRole(role.c_str())) return {};
    const OCIO::ConstColorSpaceRcPtr cs = mImpl->config->getColorSpace(role.c_str());
    return cs ? cs->getName() : std::string();
}

std::vector<std::string> ColorConfig::colorSpaces() const
{
    std::vector<std::string> names;
    const auto& c = *mImpl->config;
    const int n = c.getNumColorSpaces(OCIO::SEARCH_REFERENCE_SPACE_ALL, OCIO::COLORSPACE_ALL);
    for (int i = 0; i < n; ++i) names.emplace_back(c.getColorSpaceNameByIndex(OCIO::SEARCH_REFERENCE_SPACE_ALL, OCIO::COLORSPACE_ALL, i));
    return names;
}

std::string ColorConfig::colorSpace(const std::string& name) const
{
    const OCIO::ConstColorSpaceRcPtr cs = mImpl->config->getColorSpace(name.c_str());
    if (!cs) {
        throw ValueError("colour space '" + name + "' is not in " + origin() + " (it has " + joined(colorSpaces()) + ")");
    }
    return cs->getName();
}

bool ColorConfig::isData(const std::string& space) const
{
    const OCIO::ConstColorSpaceRcPtr cs = mImpl->config->getColorSpace(space.c_str());
    return cs && cs->isData();
}

std::string ColorConfig::defaultDisplay() const { return mImpl->config->getDefaultDisplay(); }

std::string ColorConfig::defaultView(const std::string& display) const
{
    return mImpl->config->getDefaultView(display.c_str());
}

std::string ColorConfig::displayColorSpace(const std::string& display, const std::string& view) const
{
    checkDisplayView(display, view);
    const char* space = mImpl->config->getDisplayViewColorSpaceName(display.c_str(), view.c_str());
    return space ? space : "";
}

void ColorConfig::checkDisplayView(const std::string& display, const std::string& view) const
{
    const auto& c = *mImpl->config;
    std::vector<std::string> displays, views;
    for (int i = 0; i < c.getNumDisplays(); ++i) displays.emplace_back(c.getDisplay(i));
    if (std::find(displays.begin(), displays.end(), display) == displays.end()) {
        throw ValueError("display '" + display + "' is not in " + origin() + " (it has " + joined(displays) + ")");
    }
    for (int i = 0; i < c.getNumViews(display.c_str()); ++i) views.emplace_back(c.getView(display.c_str(), i));
    if (std::find(views.begin(), views.end(), view) == views.end()) {
        throw ValueError("view '" + view + "' is not a view of display '" + display + "' in " + origin() + " (it has " +
                         joined(views) + ")");
    }
}

namespace {

std::shared_ptr<ColorTransform::Impl> makeTransform(const OCIO::ConstProcessorRcPtr& processor)
{
    auto impl = std::make_shared<ColorTransform::Impl>();
    impl->noOp = processor->isNoOp();
    impl->cpu = processor->getDefaultCPUProcessor();
    return impl;
}

} // namespace

ColorTransform ColorTransform::between(const ColorConfig& config, const std::string& from, const std::string& to)
{
    try {
        return ColorTransform(makeTransform(config.impl().config->getProcessor(from.c_str(), to.c_str())));
    } catch (const OCIO::Exception& e) {
        throw ValueError("cannot convert colour space '" + from + "' to '" + to + "' (" + e.what() + ")");
    }
}

ColorTransform ColorTransform::toDisplay(const ColorConfig& config, const std::string& from,
    const std::string& display, const std::string& view)
{
    config.checkDisplayView(display, view);
    try {
        OCIO::DisplayViewTransformRcPtr dvt = OCIO::DisplayViewTransform::Create();
        dvt->setSrc(from.c_str());
        dvt->setDisplay(display.c_str());
        dvt->setView(view.c_str());
        return ColorTransform(makeTransform(config.impl().config->getProcessor(dvt)));
    } catch (const OCIO::Exception& e) {
        throw ValueError("cannot convert colour space '" + from + "' to display '" + display + "', view '" + view +
                         "' (" + e.what() + ")");
    }
}

bool ColorTransform::isNoOp() const { return mImpl->noOp; }

Vec3d ColorTransform::apply(const Vec3d& rgb) const
{
    float v[3] = {float(rgb.x), float(rgb.y), float(rgb.z)};
    mImpl->cpu->applyRGB(v);
    return {v[0], v[1], v[2]};
}

void ColorTransform::apply(float* rgb, std::size_t count, std::size_t stride) const
{
    if (mImpl->noOp || count == 0) return;
    // OCIO's CPU processors are thread-safe: blocks of pixels in parallel (in the caller's arena).
    const auto bytes = std::ptrdiff_t(stride * sizeof(float));
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 16384), [&](const tbb::blocked_range<std::size_t>& r) {
        const long n = long(r.size());
        OCIO::PackedImageDesc desc(rgb + r.begin() * stride, n, 1, 3, OCIO::BIT_DEPTH_F32, sizeof(float), bytes, bytes * n);
        mImpl->cpu->apply(desc);
    });
}

void ColorTransform::applyPremultiplied(float* rgba, std::size_t count) const
{
    if (mImpl->noOp) return;
    // Unpremultiply, transform and premultiply each block of pixels in one pass, in parallel.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 16384), [&](const tbb::blocked_range<std::size_t>& r) {
        auto scale = [&](bool divide) {
            for (std::size_t i = r.begin(); i < r.end(); ++i) {
                float* p = rgba + 4 * i;
                const float a = p[3];
                if (!(a > 0.0f) || a == 1.0f) continue;
                for (int c = 0; c < 3; ++c) p[c] = divide ? p[c] / a : p[c] * a;
            }
        };
        scale(true);
        const long n = long(r.size());
        const auto bytes = std::ptrdiff_t(4 * sizeof(float));
        OCIO::PackedImageDesc desc(rgba + r.begin() * 4, n, 1, 3, OCIO::BIT_DEPTH_F32, sizeof(float), bytes, bytes * n);
        mImpl->cpu->apply(desc);
        scale(false);
    });
}

namespace {

/// Published primaries and white points, keyed by lower-case colour space names and aliases.
const std::map<std::string, Chromaticities>& knownChromaticities()
{
    static const std::map<std::string, Chromaticities> table = [] {
        const Vec2d acesWhite{0.32168, 0.33767}, d65{0.3127, 0.3290};
        const Chromaticities ap1{{0.713, 0.293}, {0.165, 0.830}, {0.128, 0.044}, acesWhite};
        const Chromaticities ap0{{0.7347, 0.2653}, {0.0, 1.0}, {0.0001, -0.077}, acesWhite};
        const Chromaticities rec709{{0.64, 0.33}, {0.30, 0.60}, {0.15, 0.06}, d65};
        const Chromaticities p3d65{{0.680, 0.320}, {0.265, 0.690}, {0.150, 0.060}, d65};
        const Chromaticities rec2020{{0.708, 0.292}, {0.170, 0.797}, {0.131, 0.046}, d65};
        std::map<std::string, Chromaticities> t;
        for (const char* n : {"acescg", "lin_ap1", "aces - acescg", "lin_ap1_scene"}) t[n] = ap1;
        for (const char* n : {"aces2065-1", "aces2065_1", "lin_ap0", "aces - aces2065-1", "aces"}) t[n] = ap0;
        for (const char* n : {"linear rec.709 (srgb)", "lin_rec709_srgb", "lin_rec709", "lin_srgb", "linear srgb",
                 "utility - linear - srgb", "utility - linear - rec.709", "scene-linear rec.709-srgb", "linear rec.709"})
            t[n] = rec709;
        for (const char* n : {"linear p3-d65", "lin_p3d65", "utility - linear - p3-d65"}) t[n] = p3d65;
        for (const char* n : {"linear rec.2020", "lin_rec2020", "utility - linear - rec.2020"}) t[n] = rec2020;
        return t;
    }();
    return table;
}

/// The Color Interop Forum's identifiers of the well-known spaces, by lower-case name or alias.
const std::map<std::string, std::string>& knownInteropIds()
{
    static const std::map<std::string, std::string> table = [] {
        std::map<std::string, std::string> t;
        for (const char* n : {"acescg", "lin_ap1", "aces - acescg", "lin_ap1_scene"}) t[n] = "lin_ap1_scene";
        for (const char* n : {"aces2065-1", "aces2065_1", "lin_ap0", "aces - aces2065-1", "lin_ap0_scene"}) t[n] = "lin_ap0_scene";
        for (const char* n : {"linear rec.709 (srgb)", "lin_rec709_srgb", "lin_rec709", "lin_srgb", "linear srgb", "utility - linear - srgb",
                 "utility - linear - rec.709", "scene-linear rec.709-srgb", "linear rec.709", "lin_rec709_scene"})
            t[n] = "lin_rec709_scene";
        for (const char* n : {"linear p3-d65", "lin_p3d65", "utility - linear - p3-d65", "lin_p3d65_scene"}) t[n] = "lin_p3d65_scene";
        for (const char* n : {"linear rec.2020", "lin_rec2020", "utility - linear - rec.2020", "lin_rec2020_scene"}) t[n] = "lin_rec2020_scene";
        for (const char* n : {"srgb - texture", "srgb_texture", "utility - srgb - texture", "srgb_rec709_scene", "srgb encoded rec.709 (srgb)"})
            t[n] = "srgb_rec709_scene";
        return t;
    }();
    return table;
}

} // namespace

std::string colorInteropIdOf(const ColorConfig& config, const std::string& space)
{
    const OCIO::ConstColorSpaceRcPtr cs = config.impl().config->getColorSpace(space.c_str());
    if (!cs) return "";
    if (cs->isData()) return "data";
    std::vector<std::string> names{cs->getName()};
    for (std::size_t i = 0; i < cs->getNumAliases(); ++i) names.emplace_back(cs->getAlias(i));
    for (const std::string& n : names) {
        const auto it = knownInteropIds().find(lower(n));
        if (it != knownInteropIds().end()) return it->second;
    }
    return "";
}

std::optional<Chromaticities> chromaticitiesOf(const ColorConfig& config, const std::string& space, std::string* how)
{
    const OCIO::ConstConfigRcPtr& c = config.impl().config;
    const OCIO::ConstColorSpaceRcPtr cs = c->getColorSpace(space.c_str());
    auto say = [&](const std::string& s) {
        if (how) *how = s;
    };
    if (!cs || cs->isData()) {
        say("none: '" + space + "' is a data space or unknown");
        return std::nullopt;
    }
    std::vector<std::string> names{cs->getName()};
    for (std::size_t i = 0; i < cs->getNumAliases(); ++i) names.emplace_back(cs->getAlias(i));
    for (const std::string& n : names) {
        const auto it = knownChromaticities().find(lower(n));
        if (it != knownChromaticities().end()) {
            say("published values of '" + n + "'");
            return it->second;
        }
    }
    if (c->hasRole("cie_xyz_d65_interchange")) {
        try {
            const ColorTransform toXyz = ColorTransform::between(config, cs->getName(), "cie_xyz_d65_interchange");
            Chromaticities out;
            Vec2d* targets[4] = {&out.red, &out.green, &out.blue, &out.white};
            const Vec3d inputs[4] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
            for (int i = 0; i < 4; ++i) {
                const Vec3d xyz = toXyz.apply(inputs[i]);
                const double sum = xyz.x + xyz.y + xyz.z;
                if (!(std::abs(sum) > 1e-9)) throw ValueError("degenerate primary");
                *targets[i] = Vec2d(xyz.x / sum, xyz.y / sum);
            }
            say("derived through the config's cie_xyz_d65_interchange role");
            return out;
        } catch (const Error&) {
        }
    }
    say("none: '" + space + "' is not a known space and the config has no usable cie_xyz_d65_interchange role");
    return std::nullopt;
}

} // namespace vdb_ewa
