/// @file grid_source_test.cpp
/// @brief Reading grids: value types, grid selection, and every input error path.
#include "fixtures.h"

#include <gtest/gtest.h>

#include <fstream>

using namespace vdb_ewa;
using namespace vdb_ewa::test;

namespace {

/// The message of the exception @a f throws as E; fails the test if it throws nothing.
template<typename E, typename F>
std::string messageOf(F f)
{
    try {
        f();
    } catch (const E& e) {
        return e.what();
    }
    ADD_FAILURE() << "no exception";
    return "";
}

} // namespace

TEST(GridSource, ReadsFloatDoubleAndHalfGrids)
{
    TempDir dir;
    auto f = makeBoxGrid(openvdb::Coord(0), openvdb::Coord(3), 0.5f, 0.1);
    writeGrid(f, dir.file("float.vdb"));
    auto d = openvdb::DoubleGrid::create(0.0);
    d->setName("dens");
    d->tree().setValueOn(openvdb::Coord(1, 2, 3), 0.25);
    writeGrid(d, dir.file("double.vdb"));
    auto h = makeBoxGrid(openvdb::Coord(0), openvdb::Coord(3), 0.5f, 0.1);
    h->setSaveFloatAsHalf(true);
    writeGrid(h, dir.file("half.vdb"));

    EXPECT_EQ(GridSource::open(dir.file("float.vdb")).storedType(), "float");
    const GridSource dg = GridSource::open(dir.file("double.vdb"));
    EXPECT_EQ(dg.storedType(), "double");
    EXPECT_EQ(dg.name(), "dens");
    EXPECT_EQ(dg.activeVoxelCount(), 1u);
    EXPECT_FLOAT_EQ(dg.impl().grid->tree().getValue(openvdb::Coord(1, 2, 3)), 0.25f);
    const GridSource hg = GridSource::open(dir.file("half.vdb"));
    EXPECT_EQ(hg.storedType(), "half");
    EXPECT_EQ(hg.activeVoxelCount(), 64u);
}

TEST(GridSource, PicksTheFirstFloatingPointGridOrTheNamedOne)
{
    TempDir dir;
    auto v = openvdb::Vec3SGrid::create();
    v->setName("vel");
    auto a = makeBoxGrid(openvdb::Coord(0), openvdb::Coord(1), 1.0f, 1.0);
    a->setName("a");
    auto b = makeBoxGrid(openvdb::Coord(0), openvdb::Coord(2), 1.0f, 1.0);
    b->setName("b");
    openvdb::io::File file(dir.file("multi.vdb"));
    file.write({v, a, b});
    file.close();
    EXPECT_EQ(GridSource::open(dir.file("multi.vdb")).name(), "a");
    EXPECT_EQ(GridSource::open(dir.file("multi.vdb"), "b").name(), "b");
}

TEST(GridSource, InputErrorsNameTheFileAndTheProblem)
{
    TempDir dir;
    const std::string missing = dir.file("missing.vdb");
    EXPECT_NE(messageOf<IoError>([&] { GridSource::open(missing); }).find(missing + ": no such file"), std::string::npos);

    const std::string text = dir.file("text.vdb");
    std::ofstream(text) << "this is not a VDB file\n";
    EXPECT_NE(messageOf<IoError>([&] { GridSource::open(text); }).find(text + ": cannot read VDB file"), std::string::npos);

    // Truncated: the first half of a valid file.
    const std::string good = dir.file("good.vdb"), truncated = dir.file("truncated.vdb");
    writeGrid(makeBoxGrid(openvdb::Coord(0), openvdb::Coord(31), 0.5f, 0.1), good);
    {
        std::ifstream in(good, std::ios::binary);
        std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        std::ofstream(truncated, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
    }
    EXPECT_NE(messageOf<IoError>([&] { GridSource::open(truncated); }).find(truncated + ": "), std::string::npos);

    EXPECT_NE(messageOf<InputError>([&] { GridSource::open(good, "nope"); }).find("no grid named 'nope' (grids: 'density')"),
        std::string::npos);

    const std::string ints = dir.file("int.vdb");
    auto i = openvdb::Int32Grid::create(0);
    i->setName("labels");
    writeGrid(i, ints);
    EXPECT_NE(messageOf<InputError>([&] { GridSource::open(ints); }).find("no scalar floating-point grid"), std::string::npos);
    EXPECT_NE(messageOf<InputError>([&] { GridSource::open(ints, "labels"); }).find("holds int32 values"), std::string::npos);

    const std::string ls = dir.file("ls.vdb");
    auto sphere = makeBoxGrid(openvdb::Coord(0), openvdb::Coord(1), -1.0f, 0.1);
    sphere->setGridClass(openvdb::GRID_LEVEL_SET);
    writeGrid(sphere, ls);
    EXPECT_TRUE(GridSource::open(ls).isLevelSet()) << "level sets open (rendered as surfaces)";

    EXPECT_NE(messageOf<IoError>([&] { GridSource::open(dir.file("")); }).find("is a directory"), std::string::npos);
}

TEST(GridSource, HostGridNeedsNoFile)
{
    auto g = makeBoxGrid(openvdb::Coord(0), openvdb::Coord(3), 0.5f, 0.5);
    const GridSource s = gridSourceFromOpenVDB(g);
    EXPECT_EQ(s.path(), "");
    EXPECT_EQ(s.activeVoxelCount(), 64u);
    EXPECT_NEAR(s.worldCentre().x, 0.75, 1e-12);
    EXPECT_THROW(gridSourceFromOpenVDB(nullptr), InputError);
}
