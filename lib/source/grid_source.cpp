/// @file grid_source.cpp
/// @brief Reading grids from .vdb files and from host applications.
#include "source/grid_source_impl.h"
#include "source/kernel_motion.h"
#include "source/vdb_layout_check.h"
#include "support/openvdb_tools.h"

#include <vdb_ewa/error.h>
#include <vdb_ewa/openvdb_grid.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <optional>

namespace vdb_ewa {
namespace detail {

Mat3d indexToWorldJacobian(const openvdb::math::Transform& xform, const openvdb::Vec3d& pIndex)
{
    const auto& map = *xform.baseMap();
    Mat3d a;
    for (int i = 0; i < 3; ++i) {
        openvdb::Vec3d e(0.0);
        e[i] = 1.0;
        const openvdb::Vec3d w = map.isLinear() ? map.applyJacobian(e) : map.applyJacobian(e, pIndex);
        a[i] = Vec3d(w.x(), w.y(), w.z());
    }
    return a;
}

double longestIndexAxis(const openvdb::math::Transform& xform, const openvdb::Vec3d& pIndex)
{
    const Mat3d a = indexToWorldJacobian(xform, pIndex);
    double axis = 0.0;
    for (int i = 0; i < 3; ++i) axis = std::max(axis, glm::length(a[i]));
    return axis;
}

openvdb::FloatGrid::Ptr resampledOnto(const openvdb::FloatGrid& grid, const openvdb::math::Transform& voxels)
{
    openvdb::FloatGrid::Ptr out = openvdb::FloatGrid::create(0.0f);
    out->setTransform(voxels.copy());
    openvdb::tools::resampleToMatch<openvdb::tools::BoxSampler>(grid, *out);
    return out;
}

} // namespace detail

namespace {

void initializeOpenVDB()
{
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}

bool isScalarFloatType(const std::string& type) { return type == "float" || type == "double"; }

/// GridBase::saveFloatAsHalf() without its undefined behaviour: a damaged file's bool
/// metadata may hold any byte, and a bool that is neither 0 nor 1 is undefined (clang's code
/// indexed a string literal by it: a fuzzing finding). Read the byte as a byte.
bool savedAsHalf(const openvdb::GridBase& grid)
{
    const auto meta = grid.getMetadata<openvdb::BoolMetadata>(openvdb::GridBase::META_SAVE_HALF_FLOAT);
    if (!meta) return grid.saveFloatAsHalf(); // another type: Metadata::asBool, no bool read
    unsigned char byte = 0;
    std::memcpy(&byte, &meta->value(), 1);
    return byte != 0;
}

/// Convert any supported grid to the float grid the renderer works on.
openvdb::FloatGrid::ConstPtr asFloatGrid(const openvdb::GridBase::ConstPtr& base, std::string& storedType)
{
    if (auto f = openvdb::GridBase::constGrid<openvdb::FloatGrid>(base)) {
        storedType = savedAsHalf(*f) ? "half" : "float";
        return f;
    }
    if (auto d = openvdb::GridBase::constGrid<openvdb::DoubleGrid>(base)) {
        storedType = "double";
        auto tree = std::make_shared<openvdb::FloatTree>(d->tree());
        auto f = openvdb::FloatGrid::create(tree);
        f->setTransform(d->transform().copy());
        f->setName(d->getName());
        f->setGridClass(d->getGridClass());
        return f;
    }
    return nullptr;
}

GridSource makeSource(openvdb::GridBase::ConstPtr base, const std::string& path)
{
    const std::string where = path.empty() ? std::string("host grid") : path;
    if (!base) throw InputError(where + ": null grid");
    auto impl = std::make_shared<GridSource::Impl>();
    impl->grid = asFloatGrid(base, impl->storedType);
    if (!impl->grid) {
        throw InputError(where + ": grid '" + base->getName() + "' holds " + base->valueType() +
                         " values; vdb_ewa renders scalar float or double grids");
    }
    impl->name = base->getName();
    impl->path = path;
    impl->derive();
    return GridSource(impl);
}

} // namespace

namespace {

/// The value the field reads for a stored voxel value (NaN and negative: 0; clamped above).
float fieldValue(float v)
{
    if (!(v > 0.0f)) return 0.0f;
    return std::min(v, detail::kMaxDensity);
}

/// @a grid itself if every value already reads as the field does, else a sanitised copy.
openvdb::FloatGrid::ConstPtr sanitisedField(const openvdb::FloatGrid::ConstPtr& grid)
{
    bool clean = grid->background() == 0.0f;
    for (auto it = grid->cbeginValueAll(); clean && it; ++it) {
        const float v = *it;
        if (it.isValueOn() ? fieldValue(v) != v : v != 0.0f) clean = false;
    }
    if (clean) return grid;
    openvdb::FloatGrid::Ptr copy = openvdb::FloatGrid::create(0.0f);
    copy->setTransform(grid->transform().copy());
    copy->tree().topologyUnion(grid->tree());
    auto acc = grid->getConstAccessor();
    for (auto it = copy->beginValueOn(); it; ++it) it.setValue(fieldValue(acc.getValue(it.getCoord())));
    return copy;
}

} // namespace

void GridSource::Impl::derive()
{
    // Level sets are rendered as surfaces: no density field.
    field = grid->getGridClass() == openvdb::GRID_LEVEL_SET ? grid : sanitisedField(grid);
    const auto& xform = grid->transform();
    linear = xform.isLinear();
    activeVoxels = grid->tree().activeLeafVoxelCount();
    activeTiles = grid->tree().activeTileCount();
    const openvdb::CoordBBox bbox = grid->evalActiveVoxelBoundingBox();
    // In double: CoordBBox::getCenter adds the corners as ints, which overflows past 2^30
    // (a fuzzing finding: UBSan, signed overflow).
    const openvdb::Vec3d cIndex = bbox.empty() ? openvdb::Vec3d(0.0) : 0.5 * (bbox.min().asVec3d() + bbox.max().asVec3d());
    const openvdb::Vec3d cWorld = xform.indexToWorld(cIndex);
    worldCentre = Vec3d(cWorld.x(), cWorld.y(), cWorld.z());
    indexToWorldLinear = detail::indexToWorldJacobian(xform, cIndex);
    const openvdb::Vec3d o = xform.indexToWorld(openvdb::Vec3d(0.0));
    indexToWorldOffset = Vec3d(o.x(), o.y(), o.z());
    voxelLength = std::cbrt(std::abs(glm::determinant(indexToWorldLinear)));
    if (!(voxelLength > 0.0) || !std::isfinite(voxelLength)) {
        throw InputError((path.empty() ? std::string("host grid") : path) + ": grid '" + name +
                         "' has a singular or non-finite transform");
    }
}

Vec3d GridSource::Impl::indexToWorld(const Vec3d& p) const
{
    if (linear) return indexToWorldOffset + indexToWorldLinear * p;
    const openvdb::Vec3d w = grid->transform().indexToWorld(openvdb::Vec3d(p.x, p.y, p.z));
    return Vec3d(w.x(), w.y(), w.z());
}

Vec3d GridSource::Impl::worldToIndex(const Vec3d& w) const
{
    if (linear) return glm::inverse(indexToWorldLinear) * (w - indexToWorldOffset);
    const openvdb::Vec3d p = grid->transform().worldToIndex(openvdb::Vec3d(w.x, w.y, w.z));
    return Vec3d(p.x(), p.y(), p.z());
}

namespace {

/// Check that @a path is a readable file. @throw IoError
void checkReadable(const std::string& path)
{
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) throw IoError(path + ": no such file");
    if (std::filesystem::is_directory(path, ec)) throw IoError(path + ": is a directory, not a .vdb file");
    // A FIFO, socket or device is not a .vdb file: refused before the open, which would block
    // on a FIFO with no writer where no signal can stop it.
    if (!std::filesystem::is_regular_file(path, ec)) throw IoError(path + ": not a regular file, so not a .vdb file");
    if (!std::ifstream(path, std::ios::binary)) throw IoError(path + ": cannot be read (permission denied?)");
}

/// Read grid @a name of @a path, or when @a name is empty the first grid whose value type
/// @a accepts (@a what names those for the error). @throw IoError, InputError
openvdb::GridBase::Ptr readGrid(const std::string& path, std::string name, bool (*accepts)(const std::string&),
    const std::string& what)
{
    initializeOpenVDB();
    checkReadable(path);
    detail::checkVdbLayout(path); // before OpenVDB reads lengths it never checks
    try {
        openvdb::io::File file(path);
        file.open(/*delayLoad=*/false); // read everything now, so truncation is caught here
        if (name.empty()) {
            const openvdb::GridPtrVecPtr metas = file.readAllGridMetadata();
            for (const auto& meta : *metas) {
                if (accepts(meta->valueType())) {
                    name = meta->getName();
                    break;
                }
            }
            if (name.empty()) {
                file.close();
                throw InputError(path + ": no " + what + " grid in the file");
            }
        } else if (!file.hasGrid(name)) {
            std::string names;
            for (auto it = file.beginName(); it != file.endName(); ++it) {
                names += (names.empty() ? "" : ", ") + ("'" + *it + "'");
            }
            file.close();
            throw InputError(path + ": no grid named '" + name + "' (grids: " +
                             (names.empty() ? "none" : names) + ")");
        }
        openvdb::GridBase::Ptr base = file.readGrid(name);
        file.close();
        return base;
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        throw IoError(path + ": cannot read VDB file (" + std::string(e.what()) + ")");
    }
}

/// @a transform followed by @a m (column vectors). @throw ValueError
openvdb::math::Transform::Ptr followedBy(const openvdb::math::Transform& transform, const Mat4d& m)
{
    openvdb::Mat4d rowVector; // OpenVDB's convention: the transpose; GLM's m[column][row]
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) rowVector(r, c) = m[r][c];
    openvdb::math::Transform::Ptr moved = transform.copy();
    try {
        moved->postMult(rowVector);
    } catch (const std::exception& e) {
        throw ValueError("transformed: the grid's transform cannot be moved (" + std::string(e.what()) + ")");
    }
    return moved;
}

/// @a grid read from a file, moved by @a placement (GridSource::transformed).
openvdb::GridBase::Ptr placed(openvdb::GridBase::Ptr grid, const Mat4d& placement)
{
    if (placement != Mat4d(1.0)) grid->setTransform(followedBy(grid->transform(), placement));
    return grid;
}

/// A grid sharing @a grid's tree, moved by @a m.
template <typename GridT>
typename GridT::ConstPtr moved(const typename GridT::ConstPtr& grid, const Mat4d& m)
{
    if (!grid) return grid;
    typename GridT::Ptr copy = openvdb::ConstPtrCast<GridT>(grid)->copy(); // the tree is shared, never written
    copy->setTransform(followedBy(grid->transform(), m));
    return copy;
}

/// @a impl and its colour and emission grids moved by @a m.
std::shared_ptr<GridSource::Impl> movedImpl(const GridSource::Impl& impl, const Mat4d& m)
{
    auto copy = std::make_shared<GridSource::Impl>(impl);
    copy->grid = moved<openvdb::FloatGrid>(impl.grid, m);
    copy->color = moved<openvdb::Vec3SGrid>(impl.color, m);
    copy->velocity = moved<openvdb::Vec3SGrid>(impl.velocity, m);
    copy->velocityToWorld = Mat3d(m) * impl.velocityToWorld;
    if (impl.emission) copy->emission = movedImpl(*impl.emission, m);
    if (impl.temperature) copy->temperature = movedImpl(*impl.temperature, m);
    copy->emissionColor = moved<openvdb::Vec3SGrid>(impl.emissionColor, m);
    copy->ownDensity = moved<openvdb::FloatGrid>(impl.ownDensity, m);
    for (GridSource::Impl::AddedMaterial& added : copy->addedMaterials) {
        added.density = moved<openvdb::FloatGrid>(added.density, m);
        added.volume = movedImpl(*added.volume, m);
    }
    copy->placement = m * impl.placement;
    copy->derive();
    return copy;
}

GridSource attachColor(const GridSource::Impl& impl, const openvdb::GridBase::ConstPtr& grid, const std::string& where)
{
    if (!grid) throw InputError(where + ": null colour grid");
    auto color = openvdb::GridBase::constGrid<openvdb::Vec3SGrid>(grid);
    if (!color) {
        throw InputError(where + ": colour grid '" + grid->getName() + "' holds " + grid->valueType() +
                         " values; --color needs a vec3s grid");
    }
    auto copy = std::make_shared<GridSource::Impl>(impl);
    copy->color = color;
    return GridSource(copy);
}

/// @a impl with @a base as its emission grid (@a temperature false) or temperature grid, in
/// @a impl's index space. @throw InputError
GridSource attachEmitter(const GridSource::Impl& impl, const openvdb::GridBase::ConstPtr& base, const std::string& where, bool temperature)
{
    const std::string option = temperature ? "--temperature" : "--emission-grid";
    if (!base) throw InputError(where + ": null " + (temperature ? "temperature" : "emission") + " grid");
    auto emitter = std::make_shared<GridSource::Impl>();
    emitter->grid = asFloatGrid(base, emitter->storedType);
    if (!emitter->grid) {
        throw InputError(where + ": grid '" + base->getName() + "' holds " + base->valueType() + " values; " + option +
                         " needs a float or double grid");
    }
    if (emitter->grid->getGridClass() == openvdb::GRID_LEVEL_SET) {
        throw InputError(where + ": grid '" + base->getName() + "' is a level set; " + option + " needs a fog volume");
    }
    if (emitter->grid->transform() != impl.grid->transform()) {
        // Another voxel size or placement: resampled trilinearly onto the density's voxels, so
        // that every integrator reads both in one index space.
        emitter->grid = detail::resampledOnto(*emitter->grid, impl.grid->transform());
    }
    emitter->name = base->getName();
    emitter->path = impl.path;
    emitter->derive();
    auto copy = std::make_shared<GridSource::Impl>(impl);
    (temperature ? copy->temperature : copy->emission) = emitter;
    return GridSource(copy);
}

/// @a impl with @a base (vec3s or vec3d, in @a base's own transform) as its velocity grid;
/// @a toWorld takes its vectors to world space. @throw InputError
GridSource attachVelocity(const GridSource::Impl& impl, const openvdb::GridBase::ConstPtr& base, const Mat3d& toWorld, const std::string& where)
{
    if (!base) throw InputError(where + ": null velocity grid");
    openvdb::Vec3SGrid::ConstPtr velocity = openvdb::GridBase::constGrid<openvdb::Vec3SGrid>(base);
    if (!velocity) {
        if (auto d = openvdb::GridBase::constGrid<openvdb::Vec3DGrid>(base)) {
            openvdb::Vec3SGrid::Ptr single = openvdb::Vec3SGrid::create(openvdb::Vec3s(d->background()));
            single->setTransform(d->transform().copy());
            single->setGridClass(d->getGridClass());
            single->tree().topologyUnion(d->tree());
            single->tree().voxelizeActiveTiles();
            auto acc = d->getConstAccessor();
            for (auto it = single->beginValueOn(); it; ++it) it.setValue(openvdb::Vec3s(acc.getValue(it.getCoord())));
            velocity = single;
        }
    }
    if (!velocity) {
        throw InputError(where + ": velocity grid '" + base->getName() + "' holds " + base->valueType() +
                         " values; --velocity-grid needs a vec3s or vec3d grid (or NAME.x, NAME.y, NAME.z float grids)");
    }
    auto copy = std::make_shared<GridSource::Impl>(impl);
    copy->velocity = velocity;
    copy->velocityToWorld = toWorld;
    return GridSource(copy);
}

/// The velocity grid @a name of @a path: a vector grid, or NAME.x, NAME.y, NAME.z float grids
/// joined into one (they must share a transform). @throw IoError, InputError
openvdb::GridBase::Ptr readVelocity(const std::string& path, const std::string& name)
{
    bool split = false;
    try {
        initializeOpenVDB();
        checkReadable(path);
        detail::checkVdbLayout(path);
        openvdb::io::File file(path);
        file.open(false);
        split = !file.hasGrid(name) && file.hasGrid(name + ".x") && file.hasGrid(name + ".y") && file.hasGrid(name + ".z");
        file.close();
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        throw IoError(path + ": cannot read VDB file (" + std::string(e.what()) + ")");
    }
    if (!split) return readGrid(path, name, [](const std::string&) { return false; }, "velocity");
    openvdb::FloatGrid::ConstPtr parts[3];
    for (int a = 0; a < 3; ++a) {
        const std::string part = name + "." + "xyz"[a];
        std::string stored;
        parts[a] = asFloatGrid(readGrid(path, part, isScalarFloatType, "scalar floating-point"), stored);
        if (!parts[a]) throw InputError(path + ": velocity component '" + part + "' is not a float or double grid");
        if (parts[a]->transform() != parts[0]->transform()) {
            throw InputError(path + ": velocity components '" + name + ".x', '.y' and '.z' have different transforms; they must share one");
        }
    }
    openvdb::Vec3SGrid::Ptr joined = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
    joined->setName(name);
    joined->setTransform(parts[0]->transform().copy());
    for (const auto& part : parts) joined->tree().topologyUnion(part->tree());
    joined->tree().voxelizeActiveTiles();
    auto x = parts[0]->getConstAccessor(), y = parts[1]->getConstAccessor(), z = parts[2]->getConstAccessor();
    for (auto it = joined->beginValueOn(); it; ++it) {
        const openvdb::Coord& c = it.getCoord();
        it.setValue(openvdb::Vec3s(x.getValue(c), y.getValue(c), z.getValue(c)));
    }
    return joined;
}

} // namespace

GridSource GridSource::open(const std::string& path, const std::string& gridName)
{
    return makeSource(readGrid(path, gridName, isScalarFloatType, "scalar floating-point"), path);
}

GridSource GridSource::withColorGrid(const std::string& colorName) const
{
    if (mImpl->path.empty()) throw InputError("host grid: withColorGrid needs a file; use vdb_ewa::withColorGrid with the host's grid");
    return attachColor(*mImpl, placed(readGrid(mImpl->path, colorName, [](const std::string&) { return false; }, "colour"), mImpl->placement),
        mImpl->path);
}

bool GridSource::hasColorGrid() const { return bool(mImpl->color); }

GridSource GridSource::withEmissionGrid(const std::string& emissionName) const
{
    if (mImpl->path.empty()) throw InputError("host grid: withEmissionGrid needs a file; use vdb_ewa::withEmissionGrid with the host's grid");
    return attachEmitter(*mImpl, placed(readGrid(mImpl->path, emissionName, isScalarFloatType, "scalar floating-point"), mImpl->placement),
        mImpl->path, false);
}

GridSource GridSource::withTemperatureGrid(const std::string& temperatureName) const
{
    if (mImpl->path.empty()) throw InputError("host grid: withTemperatureGrid needs a file; use vdb_ewa::withTemperatureGrid with the host's grid");
    return attachEmitter(*mImpl, placed(readGrid(mImpl->path, temperatureName, isScalarFloatType, "scalar floating-point"), mImpl->placement),
        mImpl->path, true);
}

GridSource GridSource::withVelocityGrid(const std::string& velocityName) const
{
    if (mImpl->path.empty()) throw InputError("host grid: withVelocityGrid needs a file; use vdb_ewa::withVelocityGrid with the host's grid");
    return attachVelocity(*mImpl, placed(readVelocity(mImpl->path, velocityName), mImpl->placement), Mat3d(mImpl->placement), mImpl->path);
}

bool GridSource::hasVelocityGrid() const { return bool(mImpl->velocity); }

double GridSource::voxelLength() const { return mImpl->voxelLength; }

GridSource GridSource::transformed(const Mat4d& m) const
{
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) {
            if (!std::isfinite(m[c][r])) throw ValueError("transformed: a matrix element is not finite");
        }
    if (m[0][3] != 0.0 || m[1][3] != 0.0 || m[2][3] != 0.0 || m[3][3] != 1.0) {
        throw ValueError("transformed: the matrix's last row must be 0, 0, 0, 1 (column vectors: world = M (x, y, z, 1))");
    }
    if (!(std::abs(glm::determinant(Mat3d(m))) > 1e-300)) throw ValueError("transformed: the matrix is singular");
    return GridSource(movedImpl(*mImpl, m));
}

namespace {

/// The velocity of two fog volumes summed into one field (withAddedVolume): the mean of their
/// world velocities weighted by their densities, at each active voxel of @a base's grid (a
/// volume without a velocity grid stands still). Exact where one volume is alone; where they
/// interpenetrate, their kernels move together. @a added: the other's field on @a base's
/// voxels, times @a scale; @a sum: their sum, whose active values (voxels and tiles) are the
/// voxels to fill. In world units per second or frame, on @a base's transform.
openvdb::Vec3SGrid::Ptr summedVolumeVelocity(const GridSource::Impl& base, const GridSource::Impl& other,
    const openvdb::FloatGrid& added, float scale, const openvdb::FloatGrid& sum)
{
    openvdb::Vec3SGrid::Ptr velocity = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
    velocity->setTransform(base.grid->transform().copy());
    velocity->setName("velocity");
    std::optional<detail::VelocitySampler> ownSampler, otherSampler;
    if (base.velocity) ownSampler.emplace(base);
    if (other.velocity) otherSampler.emplace(other);
    const auto own = base.field->getConstAccessor();
    const auto theirs = added.getConstAccessor();
    auto out = velocity->getAccessor();
    for (auto it = sum.cbeginValueOn(); it; ++it) {
        for (const openvdb::Coord& c : it.getBoundingBox()) { // a voxel, or each voxel of a tile
            const double a = std::max(0.0f, own.getValue(c)), b = std::max(0.0f, theirs.getValue(c) * scale);
            if (!(a + b > 0.0)) continue;
            const Vec3d p = base.indexToWorld(Vec3d(c.x(), c.y(), c.z()));
            const Vec3d va = ownSampler ? ownSampler->at(p) : Vec3d(0.0), vb = otherSampler ? otherSampler->at(p) : Vec3d(0.0);
            const Vec3d v = (a * va + b * vb) / (a + b);
            out.setValueOn(c, openvdb::Vec3s(float(v.x), float(v.y), float(v.z)));
        }
    }
    return velocity;
}

} // namespace

namespace {

/// This volume (@a base) and @a other summed into one field (withAddedVolume): the sum's Impl,
/// and @a other's density on @a base's voxels per base's voxel length (@a addedOut).
std::shared_ptr<GridSource::Impl> summedVolumes(const GridSource::Impl& base, const GridSource::Impl& other, openvdb::FloatGrid::Ptr& addedOut)
{
    using Impl = GridSource::Impl;
    const auto where = [](const Impl& impl) { return (impl.path.empty() ? std::string("host grid") : impl.path) + ": grid '" + impl.name + "'"; };
    for (const Impl* impl : {&base, &other}) {
        if (impl->grid->getGridClass() == openvdb::GRID_LEVEL_SET) {
            throw InputError(where(*impl) + " is a level set; --add-volume sums fog volumes");
        }
    }
    // The other's field on this grid's voxels, its densities per this grid's voxel length.
    openvdb::FloatGrid::Ptr added;
    if (other.field->transform() == base.grid->transform()) {
        added = other.field->deepCopy();
    } else {
        added = detail::resampledOnto(*other.field, base.grid->transform());
    }
    added->tree().voxelizeActiveTiles();
    const float scale = float(base.voxelLength / other.voxelLength);
    openvdb::FloatGrid::Ptr sum = base.field->deepCopy();
    auto acc = sum->getAccessor();
    for (auto it = added->beginValueOn(); it; ++it) {
        const openvdb::Coord c = it.getCoord();
        it.setValue(fieldValue(*it * scale));
        acc.setValueOn(c, fieldValue(acc.getValue(c) + *it));
    }
    sum->setGridClass(openvdb::GRID_FOG_VOLUME);
    sum->setName(base.name);
    auto impl = std::make_shared<Impl>(base);
    impl->grid = sum;
    impl->derive();
    if (base.velocity || other.velocity) {
        impl->velocity = summedVolumeVelocity(base, other, *added, 1.0f, *sum);
        impl->velocityToWorld = Mat3d(1.0);
    }
    addedOut = added;
    return impl;
}

} // namespace

GridSource GridSource::withAddedVolume(const GridSource& other) const
{
    openvdb::FloatGrid::Ptr added;
    auto impl = summedVolumes(*mImpl, *other.mImpl, added);
    if (!mImpl->addedMaterials.empty()) { // it takes this grid's optical model: one of the own densities
        openvdb::FloatGrid::Ptr own = mImpl->ownDensity->deepCopy();
        auto acc = own->getAccessor();
        for (auto it = added->cbeginValueOn(); it; ++it) acc.setValueOn(it.getCoord(), fieldValue(acc.getValue(it.getCoord()) + *it));
        impl->ownDensity = own;
    }
    return GridSource(impl);
}

GridSource GridSource::withAddedVolume(const GridSource& other, const Medium& medium) const
{
    for (const auto& [name, v] : {std::pair{"absorb", medium.absorb}, {"scatter", medium.scatter}, {"emission", medium.emission}}) {
        for (int c = 0; c < 3; ++c) {
            if (!(v[c] >= 0.0 && v[c] <= 1e6)) throw ValueError(std::string("withAddedVolume: the added volume's ") + name + " must be in [0, 1e6]");
        }
    }
    openvdb::FloatGrid::Ptr added;
    auto impl = summedVolumes(*mImpl, *other.mImpl, added);
    if (!impl->ownDensity) impl->ownDensity = mImpl->field;
    impl->addedMaterials.push_back({added, medium, other.mImpl});
    return GridSource(impl);
}

bool GridSource::hasEmissionGrid() const { return bool(mImpl->emission); }
bool GridSource::hasTemperatureGrid() const { return bool(mImpl->temperature); }

namespace {

/// A host's grid in @a source's world: sharing its tree, moved by source's transformed() calls.
openvdb::GridBase::ConstPtr inSourceWorld(const GridSource& source, const openvdb::GridBase::ConstPtr& grid)
{
    if (!grid || source.impl().placement == Mat4d(1.0)) return grid;
    openvdb::GridBase::Ptr copy = openvdb::ConstPtrCast<openvdb::GridBase>(grid)->copyGrid(); // the tree is shared, never written
    return placed(copy, source.impl().placement);
}

} // namespace

GridSource withEmissionGrid(const GridSource& source, openvdb::GridBase::ConstPtr emissionGrid)
{
    return attachEmitter(source.impl(), inSourceWorld(source, emissionGrid), "host grid", false);
}

GridSource withTemperatureGrid(const GridSource& source, openvdb::GridBase::ConstPtr temperatureGrid)
{
    return attachEmitter(source.impl(), inSourceWorld(source, temperatureGrid), "host grid", true);
}

GridSource withVelocityGrid(const GridSource& source, openvdb::GridBase::ConstPtr velocityGrid)
{
    return attachVelocity(source.impl(), inSourceWorld(source, velocityGrid), Mat3d(source.impl().placement), "host grid");
}

GridSource withColorGrid(const GridSource& source, openvdb::GridBase::ConstPtr colorGrid)
{
    return attachColor(source.impl(), inSourceWorld(source, colorGrid), "host grid");
}

GridSource gridSourceFromOpenVDB(openvdb::GridBase::ConstPtr grid)
{
    initializeOpenVDB();
    return makeSource(std::move(grid), "");
}

const std::string& GridSource::name() const { return mImpl->name; }
const std::string& GridSource::path() const { return mImpl->path; }
const std::string& GridSource::storedType() const { return mImpl->storedType; }
bool GridSource::isLevelSet() const { return mImpl->grid->getGridClass() == openvdb::GRID_LEVEL_SET; }
bool GridSource::isLinear() const { return mImpl->linear; }
std::uint64_t GridSource::activeVoxelCount() const { return mImpl->activeVoxels; }
std::uint64_t GridSource::activeTileCount() const { return mImpl->activeTiles; }
Vec3d GridSource::worldCentre() const { return mImpl->worldCentre; }

} // namespace vdb_ewa
