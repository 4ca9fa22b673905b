/// @file color_management.h
/// @brief OpenColorIO configs and colour conversions, with no OCIO types in the interface.
/// @note The library never reads or sets OCIO's process-wide current config (a host such as
///       Houdini or Nuke owns it): every conversion names the ColorConfig it uses.
#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "types.h"

namespace vdb_ewa {

/// An OpenColorIO config. Immutable and cheap to copy (shared); safe to use from many threads.
class VDB_EWA_API ColorConfig
{
public:
    /// The config vdb_ewa ships (share/ocio/config.ocio, compiled in): ACEScg as scene_linear,
    /// Linear Rec.709 (sRGB), ACES2065-1, and an sRGB display whose default view is the plain
    /// sRGB curve (Un-tone-mapped), with the ACES 1.0 SDR video view beside it.
    static ColorConfig shipped();
    /// @throw IoError naming @a path and OpenColorIO's message if it cannot be loaded or is invalid.
    static ColorConfig fromFile(const std::string& path);
    /// A config from its text, e.g. a host's config serialised with OCIO's Config::serialize;
    /// relative file references resolve against @a workingDir. @throw ValueError if invalid.
    static ColorConfig fromString(const std::string& text, const std::string& workingDir = "");
    /// The usual renderer precedence: @a explicitPath if not empty, then the OCIO environment
    /// variable, then shipped(). A config that cannot be used (missing, broken, an ocio:// URI,
    /// which needs OCIO 2.2) adds one line to @a warnings and falls through to the next.
    static ColorConfig resolve(const std::string& explicitPath, std::vector<std::string>& warnings);

    /// Where the config came from: a file path, or "vdb_ewa's shipped config".
    const std::string& origin() const;
    /// True for shipped() (not a file of the same text): the CLI then writes what vdb_render
    /// writes, the input space (docs/output.md#which-space-reaches-the-file).
    bool isShipped() const;
    /// The colour space of a role, e.g. "scene_linear"; empty if the config lacks the role.
    std::string roleSpace(const std::string& role) const;
    /// Canonical name of a colour space given by name, alias or role.
    /// @throw ValueError naming @a name and listing the config's colour spaces if unknown.
    std::string colorSpace(const std::string& name) const;
    /// True for data spaces (isdata: never colour-converted).
    bool isData(const std::string& space) const;
    /// All colour space names (scene- and display-referred).
    std::vector<std::string> colorSpaces() const;
    std::string defaultDisplay() const;
    std::string defaultView(const std::string& display) const;
    /// The colour space a display and view encode to (e.g. "sRGB - Display"); empty if the
    /// view names none. @throw ValueError as checkDisplayView.
    std::string displayColorSpace(const std::string& display, const std::string& view) const;
    /// @throw ValueError naming the display (or view) and listing the valid ones if unknown.
    void checkDisplayView(const std::string& display, const std::string& view) const;

    struct Impl;
    const Impl& impl() const { return *mImpl; }

private:
    explicit ColorConfig(std::shared_ptr<const Impl> impl) : mImpl(std::move(impl)) {}
    std::shared_ptr<const Impl> mImpl;
};

/// A conversion between colour spaces of one config, or from a colour space to a display and
/// view. Immutable; apply() is thread-safe.
class VDB_EWA_API ColorTransform
{
public:
    /// @throw ValueError naming the spaces if OCIO cannot build the conversion.
    static ColorTransform between(const ColorConfig& config, const std::string& from, const std::string& to);
    static ColorTransform toDisplay(const ColorConfig& config, const std::string& from, const std::string& display,
        const std::string& view);

    bool isNoOp() const;
    Vec3d apply(const Vec3d& rgb) const;
    /// Convert @a count RGB triplets in place, @a stride floats apart (3 for RGB, 4 for RGBA).
    void apply(float* rgb, std::size_t count, std::size_t stride) const;
    /// Convert premultiplied RGBA in place: unpremultiply, convert, premultiply (exact for
    /// non-linear output spaces; pixels with alpha 0 are converted as they are).
    void applyPremultiplied(float* rgba, std::size_t count) const;

    struct Impl;

private:
    explicit ColorTransform(std::shared_ptr<const Impl> impl) : mImpl(std::move(impl)) {}
    std::shared_ptr<const Impl> mImpl;
};

/// CIE 1931 xy of an RGB space's primaries and white (the EXR chromaticities attribute).
struct Chromaticities
{
    Vec2d red, green, blue, white;
};

/// Chromaticities of @a space: the published values when the space (or one of its aliases) is
/// a well-known one (ACEScg, ACES2065-1, Linear Rec.709/sRGB, Linear P3-D65, Linear Rec.2020),
/// else derived through the config's cie_xyz_d65_interchange role; none for data spaces or
/// when neither works. @a how, if given, says which.
VDB_EWA_API std::optional<Chromaticities> chromaticitiesOf(const ColorConfig& config, const std::string& space,
    std::string* how = nullptr);

/// The Color Interop Forum's identifier of @a space (its `colorInteropID` in OpenEXR files, which
/// Blender and OpenImageIO read): lin_ap1_scene for ACEScg, lin_ap0_scene, lin_rec709_scene,
/// lin_p3d65_scene, lin_rec2020_scene, srgb_rec709_scene, by the space's name or an alias;
/// "data" for data spaces; empty when the space is none of these.
VDB_EWA_API std::string colorInteropIdOf(const ColorConfig& config, const std::string& space);

} // namespace vdb_ewa
