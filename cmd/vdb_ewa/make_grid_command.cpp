/// @file make_grid_command.cpp
/// @brief `vdb_ewa make-grid KIND OUT.vdb`: the project's sample grids (grids/README.md).
#include "commands.h"
#include "exit_codes.h"

#include <vdb_ewa/vdb_ewa.h>

#include <iostream>

namespace vdb_ewa::cli {
namespace {

class MakeGridCommand : public Command
{
public:
    explicit MakeGridCommand(CLI::App& app)
    {
        mApp = app.add_subcommand("make-grid", "Write one of the project's sample fog grids");
        mApp->add_option("kind", mKind, "cloud (uniform voxels), anisotropic (voxel scale 1:2:4), "
                                        "sheared (rotated and sheared map) or tiles (constant core as active tiles)")
            ->required();
        mApp->add_option("output", mOutput, "output .vdb file")->required();
        mApp->add_option("--voxel-size", mVoxelSize, "smallest voxel edge in world units, range [0.0025, 2.4]; the cloud has about 40,000 active voxels at 0.04, 8x as many at half the size (default: 0.04)");
    }

    CLI::App* subcommand() const override { return mApp; }

    void validate() const override { sampleGridFromName(mKind); }

    int run() override
    {
        writeSampleGrid(sampleGridFromName(mKind), mOutput, mVoxelSize);
        return kExitOk;
    }

private:
    CLI::App* mApp = nullptr;
    std::string mKind, mOutput;
    double mVoxelSize = 0.04;
};

} // namespace

std::unique_ptr<Command> addMakeGridCommand(CLI::App& app) { return std::make_unique<MakeGridCommand>(app); }

} // namespace vdb_ewa::cli
