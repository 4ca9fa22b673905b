/// @file material_mix.cpp
#include "shading/material_mix.h"

#include "shading/grid_emission.h"
#include "source/source.h"
#include "support/openvdb_morphology.h"
#include "support/openvdb_tools.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <sstream>

namespace vdb_ewa {
namespace detail {

namespace {

using LeafType = openvdb::FloatTree::LeafNodeType;

/// One volume of the mix: its density on the grid's voxels (per the grid's voxel length), its
/// medium in the working space, the extinction ratio k (its extinction over the reference's),
/// its albedo relative to k (scatter / (k x reference extinction)), and where its colour and
/// emitted light come from.
struct Part
{
    openvdb::FloatGrid::ConstPtr density;
    Medium medium;
    double k = 1.0;
    Vec3d albedo{0.0};
    const GridSource::Impl* volume = nullptr; ///< colour, emission and temperature grids
};

double mean(const Vec3d& v) { return (v.x + v.y + v.z) / 3.0; }

/// Call @a fill(leaf) for every leaf of @a grid's tree, in parallel; @a grid's topology is fixed.
template <typename GridT, typename Fill>
void forEachLeaf(GridT& grid, const Fill& fill)
{
    std::vector<typename GridT::TreeType::LeafNodeType*> leaves;
    grid.tree().getNodes(leaves);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size(), 16), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t l = r.begin(); l < r.end(); ++l) fill(*leaves[l]);
    });
}

/// A float grid on @a like's transform, with @a topology's active voxels (no tiles).
template <typename GridT>
typename GridT::Ptr onTopology(const openvdb::FloatGrid& like, const openvdb::FloatGrid& topology)
{
    typename GridT::Ptr out = GridT::create();
    out->setTransform(like.transform().copy());
    out->tree().topologyUnion(topology.tree());
    out->tree().voxelizeActiveTiles();
    return out;
}

/// @a grid (an emission or temperature grid in its own index space) on @a base's voxels,
/// trilinear where the transforms differ.
openvdb::FloatGrid::ConstPtr onVoxelsOf(const openvdb::FloatGrid::ConstPtr& grid, const openvdb::FloatGrid& base)
{
    if (grid->transform() == base.transform()) return grid;
    return resampledOnto(*grid, base.transform());
}

/// A colour grid on @a topology's voxels and the shell a voxel around them (which trilinear
/// lookups reach): at each, numerator / denominator of @a ratioAt(ijk, numerator) (which adds
/// to numerator and returns the denominator), or where that voxel has none, the ratio of the
/// sums over its 3 x 3 x 3 neighbourhood.
template <typename MakeRatio>
openvdb::Vec3SGrid::Ptr ratioGrid(const openvdb::FloatGrid& topology, const MakeRatio& makeRatio)
{
    openvdb::FloatGrid::Ptr shell = topology.deepCopy();
    openvdb::tools::dilateActiveValues(shell->tree(), 1, openvdb::tools::NN_FACE_EDGE_VERTEX, openvdb::tools::IGNORE_TILES);
    openvdb::Vec3SGrid::Ptr out = onTopology<openvdb::Vec3SGrid>(topology, *shell);
    forEachLeaf(*out, [&](openvdb::Vec3STree::LeafNodeType& leaf) {
        auto ratioAt = makeRatio(); // one per thread: it holds accessors
        for (auto it = leaf.beginValueOn(); it; ++it) {
            const openvdb::Coord ijk = it.getCoord();
            Vec3d numerator(0.0);
            double denominator = ratioAt(ijk, numerator);
            if (!(denominator > 0.0)) {
                for (int x = -1; x <= 1; ++x)
                    for (int y = -1; y <= 1; ++y)
                        for (int z = -1; z <= 1; ++z) denominator += ratioAt(ijk.offsetBy(x, y, z), numerator);
            }
            const Vec3d c = denominator > 0.0 ? numerator / denominator : Vec3d(0.0);
            it.setValue(openvdb::Vec3s(float(c.x), float(c.y), float(c.z)));
        }
    });
    return out;
}

/// The volumes' media as the mix weighs them: the parts (the grid's own densities with the
/// render's medium, then each added volume's, in the working space; @a channel >= 0: every
/// medium grey at that channel's coefficients), the reference extinction (the grid's own, or
/// the first part's that has one), each part's k and albedo, and a line for each part whose
/// extinction is not in proportion to the reference.
struct Media
{
    std::vector<Part> parts;
    Vec3d reference{0.0};
    std::vector<std::string> notInProportion;
};

Media mediaOf(const GridSource::Impl& grid, const RenderSettings& settings, int channel)
{
    Media out;
    std::vector<Part>& parts = out.parts;
    parts.push_back({grid.ownDensity, settings.medium, 1.0, Vec3d(0.0), &grid});
    for (const GridSource::Impl::AddedMaterial& m : grid.addedMaterials) {
        Medium working = m.medium;
        working.absorb = workingColor(settings.inputToWorking, m.medium.absorb);
        working.scatter = workingColor(settings.inputToWorking, m.medium.scatter);
        working.emission = workingColor(settings.inputToWorking, m.medium.emission);
        parts.push_back({m.density, working, 1.0, Vec3d(0.0), m.volume.get()});
    }
    if (channel >= 0) { // every medium grey at one channel's coefficients: the mix exact in that channel
        for (Part& p : parts) {
            for (Vec3d* v : {&p.medium.absorb, &p.medium.scatter, &p.medium.emission}) *v = Vec3d((*v)[channel]);
        }
    }
    Vec3d& reference = out.reference;
    reference = parts[0].medium.extinction();
    for (const Part& p : parts) {
        if (mean(reference) > 0.0) break;
        reference = p.medium.extinction();
    }
    for (Part& p : parts) {
        const Vec3d extinction = p.medium.extinction();
        p.k = mean(reference) > 0.0 ? mean(extinction) / mean(reference) : 1.0;
        bool proportional = true;
        for (int c = 0; c < 3; ++c) {
            const double scaled = p.k * reference[c];
            p.albedo[c] = scaled > 0.0 ? p.medium.scatter[c] / scaled : 0.0;
            proportional = proportional && std::abs(extinction[c] - scaled) <= 1e-6 * std::max(extinction[c], scaled);
        }
        if (!proportional) {
            std::ostringstream w;
            w << "the volume " << (p.volume->path.empty() ? std::string("(host grid)") : p.volume->path) << " ('" << p.volume->name
              << "'): its extinction (" << extinction.x << "," << extinction.y << "," << extinction.z
              << ") is not in proportion to the input's: a deep image, which cannot be rendered channel by channel, takes it grey, "
                 "at its mean (light maps march one extinction colour); its scattered light is kept";
            out.notInProportion.push_back(w.str());
        }
    }
    return out;
}

} // namespace

bool extinctionsInProportion(const GridSource::Impl& grid, const RenderSettings& settings)
{
    return mediaOf(grid, settings, -1).notInProportion.empty();
}

MixedFrame mixMaterials(const GridSource::Impl& grid, const RenderSettings& settings, int channel)
{
    MixedFrame out;
    out.settings = settings;
    Media media = mediaOf(grid, settings, channel);
    const std::vector<Part>& parts = media.parts;
    const Vec3d reference = media.reference;
    out.warnings = std::move(media.notInProportion);

    // The density: sum_j k_j rho_j on every part's voxels.
    openvdb::FloatGrid::Ptr density = grid.ownDensity->deepCopy();
    for (std::size_t j = 1; j < parts.size(); ++j) density->tree().topologyUnion(parts[j].density->tree());
    density->tree().voxelizeActiveTiles();
    forEachLeaf(*density, [&](LeafType& leaf) {
        std::vector<openvdb::FloatGrid::ConstAccessor> acc;
        for (const Part& p : parts) acc.push_back(p.density->getConstAccessor());
        for (auto it = leaf.beginValueOn(); it; ++it) {
            double sum = 0.0;
            for (std::size_t j = 0; j < parts.size(); ++j) sum += parts[j].k * std::max(0.0, double(acc[j].getValue(it.getCoord())));
            it.setValue(float(std::min(sum, double(kMaxDensity))));
        }
    });
    density->setName(grid.name);
    density->setGridClass(openvdb::GRID_FOG_VOLUME);

    // The colour: each voxel's albedo x colour, weighed by k_j rho_j.
    openvdb::Vec3SGrid::Ptr color = ratioGrid(*density, [&] {
        std::vector<openvdb::FloatGrid::ConstAccessor> acc;
        std::vector<MaterialColor> colors;
        for (const Part& p : parts) {
            acc.push_back(p.density->getConstAccessor());
            colors.emplace_back(*p.volume);
        }
        return [&, acc, colors](const openvdb::Coord& ijk, Vec3d& weighted) mutable {
            double sum = 0.0;
            const Vec3d world = grid.indexToWorld(Vec3d(ijk.x(), ijk.y(), ijk.z()));
            for (std::size_t j = 0; j < parts.size(); ++j) {
                const double w = parts[j].k * std::max(0.0, double(acc[j].getValue(ijk)));
                if (!(w > 0.0)) continue;
                const Vec3d c = parts[j].volume->color ? workingColor(settings.inputToWorking, colors[j].at(world)) : Vec3d(1.0);
                weighted += w * parts[j].albedo * c;
                sum += w;
            }
            return sum;
        };
    });
    color->setName("mixed albedo");

    auto mixed = std::make_shared<GridSource::Impl>(grid);
    mixed->addedMaterials.clear();
    mixed->ownDensity = nullptr;
    mixed->grid = density;
    mixed->color = color;
    out.settings.inputToWorking = Mat3d(1.0);
    out.settings.medium.absorb = Vec3d(0.0);
    out.settings.medium.scatter = reference;
    out.settings.medium.emission = Vec3d(0.0);

    // The emitted light, radiance per voxel length: each part's constant emission x density,
    // emission grid and blackbody (at each voxel's temperature), on the grid's voxels.
    bool emits = false;
    for (const Part& p : parts) emits = emits || p.medium.emission != Vec3d(0.0) || (p.volume != &grid && (p.volume->emission || p.volume->temperature));
    if (emits) {
        const EmissionModel model(settings);
        struct Emitter
        {
            openvdb::FloatGrid::ConstPtr values;
            double scale;           ///< per the grid's voxel length
            bool temperature;
        };
        std::vector<Emitter> emitters;
        for (const Part& p : parts) {
            const double scale = grid.voxelLength / p.volume->voxelLength;
            if (p.volume->emission) emitters.push_back({onVoxelsOf(p.volume->emission->field, *density), scale, false});
            if (p.volume->temperature) emitters.push_back({onVoxelsOf(p.volume->temperature->field, *density), scale, true});
        }
        openvdb::FloatGrid::Ptr magnitude = density->deepCopy();
        for (const Emitter& e : emitters) magnitude->tree().topologyUnion(e.values->tree());
        magnitude->tree().voxelizeActiveTiles();
        // Radiance per voxel length at a voxel; one per thread (it holds accessors).
        const auto makeRadiance = [&] {
            std::vector<openvdb::FloatGrid::ConstAccessor> acc, em;
            for (const Part& p : parts) acc.push_back(p.density->getConstAccessor());
            for (const Emitter& e : emitters) em.push_back(e.values->getConstAccessor());
            return [&, acc, em](const openvdb::Coord& ijk) mutable {
                Vec3d e(0.0);
                for (std::size_t j = 0; j < parts.size(); ++j) e += std::max(0.0, double(acc[j].getValue(ijk))) * parts[j].medium.emission;
                for (std::size_t i = 0; i < emitters.size(); ++i) {
                    if (!em[i].isValueOn(ijk)) continue;
                    const double v = double(em[i].getValue(ijk));
                    e += emitters[i].scale * (emitters[i].temperature ? model.blackbody(v) : model.emitted(v));
                }
                return glm::min(e, Vec3d(kMaxRadiance));
            };
        };
        forEachLeaf(*magnitude, [&](LeafType& leaf) {
            auto radianceAt = makeRadiance();
            for (auto it = leaf.beginValueOn(); it; ++it) {
                const Vec3d e = radianceAt(it.getCoord());
                it.setValue(float(e.x + e.y + e.z));
            }
        });
        // Its colour: radiance over the sum of its channels.
        openvdb::Vec3SGrid::Ptr chroma = ratioGrid(*magnitude, [&] {
            return [radianceAt = makeRadiance()](const openvdb::Coord& ijk, Vec3d& sum) mutable {
                const Vec3d e = radianceAt(ijk);
                sum += e;
                return e.x + e.y + e.z;
            };
        });
        auto emission = std::make_shared<GridSource::Impl>();
        emission->grid = magnitude;
        emission->name = "mixed emission";
        emission->path = grid.path;
        emission->derive();
        mixed->emission = emission;
        mixed->temperature = nullptr;
        mixed->emissionColor = chroma;
        out.settings.gridEmission.color = Vec3d(1.0);
        out.settings.gridEmission.intensity = 1.0;
    }
    mixed->derive();
    out.grid = mixed;
    return out;
}

} // namespace detail
} // namespace vdb_ewa
