/// @file grid_source_test.cpp
/// @brief Reading grids: value types, grid selection, and every input error path.
#include "fixtures.h"

#include <gtest/gtest.h>
#include <openvdb/io/Stream.h>

#include <chrono>
#include <cstring>
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

TEST(GridSource, DamagedHeadersAreRefusedBeforeOpenVDBReadsThem)
{
    // OpenVDB takes lengths from bytes it never read: cuts of a 200 KB file between bytes 126
    // and 350 made it allocate 1-20 GB for 1-30 s before its error. The header is walked first
    // (lib/source/vdb_layout_check.h): every cut is "damaged VDB file", at once.
    TempDir dir;
    const std::string good = dir.file("good.vdb"), cut = dir.file("cut.vdb");
    writeSampleGrid(SampleGrid::Cloud, good, 0.08);
    std::ifstream in(good, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    ASSERT_GT(bytes.size(), 2000u);
    std::vector<std::size_t> lengths;
    for (std::size_t n = 0; n < 600; ++n) lengths.push_back(n);
    for (std::size_t k = 1; k < 40; ++k) lengths.push_back(600 + k * (bytes.size() - 601) / 40);
    lengths.push_back(bytes.size() - 1);
    const auto start = std::chrono::steady_clock::now();
    for (const std::size_t n : lengths) {
        std::ofstream(cut, std::ios::binary | std::ios::trunc) << bytes.substr(0, n);
        const std::string m = messageOf<IoError>([&] { GridSource::open(cut); });
        EXPECT_NE(m.find(cut + ": damaged VDB file: "), std::string::npos) << "cut at " << n << ": " << m;
    }
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 10.0);

    // Lengths and counts that claim more than the file has: the grid name's length, the grid
    // count, the file metadata's count (the byte offsets of this writer's layout).
    const std::size_t nameAt = bytes.find("density") - 4, countAt = nameAt - 4, metaAt = countAt - 4;
    ASSERT_EQ(bytes.substr(metaAt, 4), std::string(4, '\0')) << "no file metadata: count 0";
    for (const std::size_t at : {nameAt, countAt, metaAt}) {
        std::string damaged = bytes;
        damaged.replace(at, 4, "\xf0\xff\xff\x7f", 4);
        std::ofstream(cut, std::ios::binary | std::ios::trunc) << damaged;
        const std::string m = messageOf<IoError>([&] { GridSource::open(cut); });
        EXPECT_NE(m.find("damaged VDB file"), std::string::npos) << "at " << at << ": " << m;
        EXPECT_NE(m.find("claims"), std::string::npos) << "at " << at << ": " << m;
    }
    // The root node's tile count (after the transform's 120 bytes, the buffer count and the
    // background): 2^31 tiles took OpenVDB 34 s to refuse, read one by one.
    const std::size_t tilesAt = bytes.find("UniformScaleMap") + 15 + 120 + 4 + 4;
    std::string damaged = bytes;
    damaged.replace(tilesAt, 4, "\xff\xff\xff\x7f", 4);
    std::ofstream(cut, std::ios::binary | std::ios::trunc) << damaged;
    const std::string m = messageOf<IoError>([&] { GridSource::open(cut); });
    EXPECT_NE(m.find("the root node at byte " + std::to_string(tilesAt) + " claims 2147483647 tiles"), std::string::npos) << m;

    // OpenVDB's delayed-load metadata (type name, value size, leaf count, the mask's block size
    // and bytes, ...): a leaf count of 2^32 made OpenVDB allocate 4 GB (found by fuzz_vdb_file),
    // and so does a block size claiming more than the metadata holds.
    const std::size_t delayedAt = bytes.find("__delayedload");
    ASSERT_NE(delayedAt, std::string::npos);
    const std::size_t leavesAt = delayedAt + 13 + 4, maskBytesAt = leavesAt + 4;
    for (const std::size_t at : {leavesAt, maskBytesAt}) {
        std::string delayed = bytes;
        delayed.replace(at, 4, "\xff\xff\xff\x7f", 4);
        std::ofstream(cut, std::ios::binary | std::ios::trunc) << delayed;
        const std::string e = messageOf<IoError>([&] { GridSource::open(cut); });
        EXPECT_NE(e.find("damaged VDB file: the delayed-load metadata"), std::string::npos) << "at " << at << ": " << e;
    }
}

// Below the root node OpenVDB trusts its sizes too: a leaf's compressed-block size larger than
// the file made it allocate that much, a raw block's size larger than the node overran its
// buffer (heap corruption), a garbage child mask read thousands of nodes. The topology and the
// leaf buffers are walked first (lib/source/vdb_layout_check.cpp), and every real asset and
// seed still passes.
TEST(GridSource, DamagedNodesAreRefusedBeforeOpenVDBReadsThem)
{
    TempDir dir;
    const std::string good = dir.file("good.vdb"), bad = dir.file("bad.vdb");
    writeSampleGrid(SampleGrid::Cloud, good, 0.08);
    std::ifstream in(good, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const auto int64At = [&](std::size_t at) {
        std::int64_t v = 0;
        std::memcpy(&v, bytes.data() + at, 8);
        return v;
    };
    // The grid descriptor's offsets follow its type name and an empty instance-parent name.
    const std::size_t offsetsAt = bytes.find("Tree_float_5_4_3") + 16 + 4;
    const std::size_t dataAt = std::size_t(int64At(offsetsAt + 8));
    // The first leaf's buffer: its value mask, the compression metadata (0: all values), the
    // zip block's signed size.
    ASSERT_EQ(bytes[dataAt + 64], '\0');
    const std::size_t blockAt = dataAt + 65;
    const std::int64_t block = int64At(blockAt);
    ASSERT_NE(block, 0);
    // The first root child's child mask: after the transform, the buffer count, the
    // background, the tile and child counts (no tiles) and the child's origin.
    const std::size_t childMaskAt = bytes.find("UniformScaleMap") + 15 + 120 + 4 + 4 + 8 + 12;
    ASSERT_EQ(bytes.substr(childMaskAt - 20, 4), std::string(4, '\0')) << "no root tiles";

    struct Damage
    {
        std::size_t at;
        std::string with, expect;
    };
    const std::int64_t huge = std::int64_t(1) << 40, rawOverrun = -4096;
    const std::vector<Damage> damages{
        {blockAt, std::string(reinterpret_cast<const char*>(&huge), 8), "the compressed block at byte " + std::to_string(blockAt) + " claims"},
        {blockAt, std::string(reinterpret_cast<const char*>(&rawOverrun), 8), "the raw block at byte " + std::to_string(blockAt) + " holds 4096 bytes"},
        {childMaskAt, std::string(4096, '\xff'), "children"},
        {dataAt + 3, std::string(1, char(bytes[dataAt + 3] ^ 1)), "differs from the tree's topology"},
    };
    for (const Damage& d : damages) {
        std::string damaged = bytes;
        damaged.replace(d.at, d.with.size(), d.with);
        std::ofstream(bad, std::ios::binary | std::ios::trunc) << damaged;
        const std::string m = messageOf<IoError>([&] { GridSource::open(bad); });
        EXPECT_NE(m.find(bad + ": damaged VDB file: "), std::string::npos) << m;
        EXPECT_NE(m.find(d.expect), std::string::npos) << m;
    }
    // A tree buffer count other than 1 (OpenVDB warns and reads on: with a garbage root behind
    // it, 20 GB and 60 s) does not stop the walk.
    const std::size_t bufferCountAt = childMaskAt - 12 - 8 - 4 - 4;
    std::string twice = bytes;
    twice.replace(bufferCountAt, 4, "\x02\0\0\0", 4);
    twice.replace(blockAt, 8, std::string(reinterpret_cast<const char*>(&huge), 8));
    std::ofstream(bad, std::ios::binary | std::ios::trunc) << twice;
    EXPECT_NE(messageOf<IoError>([&] { GridSource::open(bad); }).find("the compressed block at byte"), std::string::npos);
    // A root tile's active flag is read as a bool: anything but 0 or 1 is undefined behaviour.
    auto tiled = openvdb::FloatGrid::create(0.0f);
    tiled->setName("density");
    tiled->tree().addTile(3, openvdb::Coord(8192, 0, 0), 1.0f, true);
    tiled->tree().setValueOn(openvdb::Coord(1, 2, 3), 0.5f);
    writeGrid(tiled, bad);
    std::ifstream tin(bad, std::ios::binary);
    std::string tile((std::istreambuf_iterator<char>(tin)), std::istreambuf_iterator<char>());
    tin.close();
    const std::size_t activeAt = tile.find("UniformScaleMap") + 15 + 120 + 4 + 4 + 8 + 12 + 4;
    ASSERT_EQ(tile[activeAt], '\1');
    tile[activeAt] = '\x7f';
    std::ofstream(bad, std::ios::binary | std::ios::trunc) << tile;
    EXPECT_NE(messageOf<IoError>([&] { GridSource::open(bad); }).find("a root tile's active flag"), std::string::npos);
    // A cut anywhere in the leaf buffers.
    for (std::size_t k = 1; k < 20; ++k) {
        std::ofstream(bad, std::ios::binary | std::ios::trunc) << bytes.substr(0, dataAt + k * (bytes.size() - dataAt) / 20);
        EXPECT_NE(messageOf<IoError>([&] { GridSource::open(bad); }).find("damaged VDB file"), std::string::npos) << k;
    }
    // No false alarms: the undamaged file and every shared asset open.
    EXPECT_NO_THROW(GridSource::open(good));
    const std::string assets = assetsDir();
    if (assets.empty()) return;
    for (const auto& e : std::filesystem::directory_iterator(assets)) {
        if (e.path().extension() != ".vdb") continue;
        EXPECT_NO_THROW(GridSource::open(e.path().string())) << e.path();
    }
}

namespace {

/// The bytes of the file at @a path.
std::string fileBytes(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

/// @a bytes with the 8 bytes at @a at replaced by @a v.
std::string withInt64(std::string bytes, std::size_t at, std::int64_t v)
{
    std::memcpy(bytes.data() + at, &v, 8);
    return bytes;
}

std::int64_t int64In(const std::string& bytes, std::size_t at)
{
    std::int64_t v = 0;
    std::memcpy(&v, bytes.data() + at, 8);
    return v;
}

/// The message GridSource::open gives for a file holding @a bytes (empty when it opens).
std::string openMessage(const std::string& path, const std::string& bytes, const std::string& grid = "")
{
    std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
    try {
        GridSource::open(path, grid);
    } catch (const std::exception& e) {
        return e.what();
    }
    return "";
}

} // namespace

// The same damage below the root with every compression OpenVDB writes (none, zip, blosc, each
// with and without active-mask compression) and with half floats: a zip or blosc block size
// claiming more than the file, a garbage child mask, cuts in the buffers.
TEST(GridSource, DamagedNodesAreRefusedWhateverTheCompression)
{
    TempDir dir;
    const std::string sample = dir.file("sample.vdb"), file = dir.file("variant.vdb");
    writeSampleGrid(SampleGrid::Tiles, sample, 0.08);
    openvdb::io::File src(sample);
    src.open();
    const auto grid = src.readGrid("density");
    src.close();
    grid->clearGridClass(); // Archive::setGridCompression drops zip for fog volumes
    namespace io = openvdb::io;
    for (const std::uint32_t compression : std::initializer_list<std::uint32_t>{io::COMPRESS_NONE, io::COMPRESS_ACTIVE_MASK,
             io::COMPRESS_ZIP, io::COMPRESS_ZIP | io::COMPRESS_ACTIVE_MASK, io::COMPRESS_BLOSC, io::COMPRESS_BLOSC | io::COMPRESS_ACTIVE_MASK}) {
        for (const bool half : {false, true}) {
            SCOPED_TRACE("compression " + std::to_string(compression) + (half ? ", half floats" : ""));
            grid->setSaveFloatAsHalf(half);
            {
                io::File out(file);
                out.setCompression(compression);
                out.write({grid});
            }
            const std::string bytes = fileBytes(file);
            EXPECT_EQ(openMessage(file, bytes), "");
            const std::size_t offsetsAt = bytes.find("Tree_float_5_4_3") + 16 + (half ? 10 : 0) + 4;
            const std::size_t dataAt = std::size_t(int64In(bytes, offsetsAt + 8));
            // The first root child's child mask (no root tiles).
            const std::size_t countsAt = bytes.find("UniformScaleMap") + 15 + 120 + 4 + 4;
            ASSERT_EQ(bytes.substr(countsAt, 4), std::string(4, '\0'));
            std::string damaged = bytes;
            damaged.replace(countsAt + 8 + 12, 4096, 4096, '\xff');
            const std::string mask = openMessage(file, damaged);
            EXPECT_NE(mask.find(file + ": damaged VDB file: "), std::string::npos) << mask;
            // The first leaf's buffer: value mask, compression metadata, inactive values and
            // selection mask as io::readCompressedValues reads them, then the block size.
            const int meta = bytes[dataAt + 64];
            std::size_t blockAt = dataAt + 65 + (meta == 2 || meta == 4 ? 4 : meta == 5 ? 8 : 0) + (meta >= 3 && meta <= 5 ? 64 : 0);
            if (compression & (io::COMPRESS_ZIP | io::COMPRESS_BLOSC)) {
                const std::string huge = openMessage(file, withInt64(bytes, blockAt, std::int64_t(1) << 40));
                EXPECT_NE(huge.find(file + ": damaged VDB file: the compressed block at byte " + std::to_string(blockAt) + " claims"),
                          std::string::npos) << huge;
            }
            for (std::size_t k = 1; k < 8; ++k) {
                const std::string cut = openMessage(file, bytes.substr(0, dataAt + k * (bytes.size() - dataAt) / 8));
                EXPECT_NE(cut.find(file + ": damaged VDB file: "), std::string::npos) << k << ": " << cut;
            }
        }
    }
}

// The walk reads what OpenVDB 10 reads, where the two could part: an instance grid (no
// topology of its own), the half-float flag (the grid's is_saved_as_half_float metadata, not
// the type name), fixed-size metadata (TypedMetadata reads sizeof(T) whatever the stored size),
// a blosc header's own block length (blosc_decompress_ctx trusts it), and the data offset
// (OpenVDB reads the buffers straight after the topology).
TEST(GridSource, LayoutWalkReadsWhatOpenVDBReads)
{
    TempDir dir;
    const std::string file = dir.file("grid.vdb");
    auto grid = makeBoxGrid(openvdb::Coord(0), openvdb::Coord(40), 0.5f, 0.1);
    auto instance = grid->copyGrid(); // shares the tree: written as an instance of "density"
    instance->setName("copy");
    {
        openvdb::io::File out(file);
        out.write({grid, instance});
    }
    const std::string instanced = fileBytes(file);
    ASSERT_NE(instanced.find("copy"), std::string::npos);
    EXPECT_EQ(openMessage(file, instanced, "copy"), "");
    EXPECT_EQ(openMessage(file, instanced, "density"), "");

    grid->setSaveFloatAsHalf(true);
    writeGrid(grid, file);
    const std::string half = fileBytes(file);
    EXPECT_EQ(openMessage(file, half), "");
    // is_saved_as_half_float: name, type "bool", size 1, value 1. At 0 OpenVDB reads 4-byte
    // floats where the nodes hold halves (the walk used to take the flag from the type name).
    const std::size_t flagAt = half.find("is_saved_as_half_float") + 22 + 4 + 4 + 4;
    ASSERT_EQ(half.substr(flagAt - 8, 9), std::string("bool\1\0\0\0\1", 9));
    std::string full = half;
    full[flagAt] = '\0';
    const std::string asFull = openMessage(file, full);
    EXPECT_NE(asFull.find(file + ": damaged VDB file: "), std::string::npos) << asFull;

    grid->setSaveFloatAsHalf(false);
    writeGrid(grid, file);
    const std::string bytes = fileBytes(file);
    const std::size_t offsetsAt = bytes.find("Tree_float_5_4_3") + 16 + 4;
    const std::size_t dataAt = std::size_t(int64In(bytes, offsetsAt + 8));

    // An int64 value stored as 12 bytes, the grid's offsets moved to match: OpenVDB reads 8 and
    // takes the other 4 as the next name's length.
    const std::size_t countAt = bytes.find("file_voxel_count");
    ASSERT_NE(countAt, std::string::npos);
    const std::size_t sizeAt = countAt + 16 + 4 + 5;
    ASSERT_EQ(bytes.substr(sizeAt - 5, 9), std::string("int64\x08\0\0\0", 9));
    std::string longer = bytes;
    longer[sizeAt] = '\x0c';
    longer.insert(sizeAt + 4 + 8, std::string(4, '\0'));
    longer = withInt64(longer, offsetsAt + 8, std::int64_t(dataAt) + 4);
    longer = withInt64(longer, offsetsAt + 16, int64In(bytes, offsetsAt + 16) + 4);
    EXPECT_NE(openMessage(file, longer).find("damaged VDB file: a int64 metadata value at byte " + std::to_string(sizeAt) +
                                             " claims 12 bytes, not 8"),
              std::string::npos);

    // The first leaf's blosc block (value mask, metadata 0, size, then blosc's 16-byte header
    // with the block's length at byte 12) claiming 64 bytes more than it holds.
    ASSERT_EQ(bytes[dataAt + 64], '\0');
    const std::size_t blockAt = dataAt + 65;
    std::uint32_t length = 0;
    std::memcpy(&length, bytes.data() + blockAt + 8 + 12, 4);
    ASSERT_EQ(std::int64_t(length), int64In(bytes, blockAt));
    std::string header = bytes;
    length += 64;
    std::memcpy(header.data() + blockAt + 8 + 12, &length, 4);
    EXPECT_NE(openMessage(file, header).find("damaged VDB file: the blosc block at byte " + std::to_string(blockAt) + " holds"),
              std::string::npos);

    // A data offset other than the topology's end.
    EXPECT_NE(openMessage(file, withInt64(bytes, offsetsAt + 8, std::int64_t(dataAt) + 8))
                  .find("damaged VDB file: the tree's topology ends at byte " + std::to_string(dataAt)),
              std::string::npos);
}

// Files older than format 222 (OpenVDB 2.0) are refused with one line before OpenVDB reads
// them: the walk does not know their layout, and a damaged one (a fuzzing finding, version 0)
// made OpenVDB read for 10 s and allocate 3.4 GB.
TEST(GridSource, FormatsOlderThanOpenVDB2AreRefused)
{
    TempDir dir;
    const std::string file = dir.file("old.vdb");
    writeGrid(makeBoxGrid(openvdb::Coord(0), openvdb::Coord(8), 0.5f, 0.1), file);
    const std::string bytes = fileBytes(file);
    EXPECT_EQ(openMessage(file, bytes), "");
    for (const std::uint32_t version : {0u, 211u, 221u}) {
        std::string old = bytes;
        std::memcpy(old.data() + 8, &version, 4);
        EXPECT_EQ(openMessage(file, old), file + ": VDB file format version " + std::to_string(version) +
                                              " is older than OpenVDB 2.0's (222) and is not read; re-save it with OpenVDB 2.0 or later");
    }
}

// The grid's centre is taken in double: two voxels near +-1.4e9 (a fuzzing finding) overflowed
// CoordBBox::getCenter's int sum, UB that put the default camera's target far off the grid.
TEST(GridSource, CentreOfAGridNearTheIndexLimitsIsExact)
{
    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->tree().setValueOn(openvdb::Coord(1400000000, -1400000000, 7), 1.0f);
    grid->tree().setValueOn(openvdb::Coord(1400000010, -1400000010, 9), 1.0f);
    const Vec3d c = gridSourceFromOpenVDB(grid).worldCentre();
    EXPECT_DOUBLE_EQ(c.x, 1400000005.0);
    EXPECT_DOUBLE_EQ(c.y, -1400000005.0);
    EXPECT_DOUBLE_EQ(c.z, 8.0);
}

// io::Stream writes no grid offsets: each grid follows its descriptor inline and File::open
// streams them all in. One flipped offsets flag put a file outside the layout walk, and a bool
// metadata byte of 'y' (a fuzzing finding) reached GridBase::saveFloatAsHalf() as an undefined
// bool. Such streams are walked grid after grid.
TEST(GridSource, StreamsWithoutOffsetsAreWalkedToo)
{
    TempDir dir;
    const std::string file = dir.file("stream.vdb");
    auto fog = makeBoxGrid(openvdb::Coord(0), openvdb::Coord(20), 0.5f, 0.1);
    fog->setName("fog");
    auto density = makeBoxGrid(openvdb::Coord(-9), openvdb::Coord(9), 1.0f, 0.1);
    density->setName("density");
    density->setSaveFloatAsHalf(false); // written as bool metadata
    {
        std::ofstream out(file, std::ios::binary);
        openvdb::io::Stream(out).write(openvdb::GridCPtrVec{fog, density});
    }
    const std::string bytes = fileBytes(file);
    ASSERT_EQ(bytes[20], '\0') << "the header's grid offsets flag";
    EXPECT_EQ(openMessage(file, bytes, "density"), "") << "an undamaged stream opens";
    EXPECT_EQ(GridSource::open(file, "density").activeVoxelCount(), density->activeVoxelCount());

    // The second grid's half-float flag: a bool whose byte is 'y'.
    const std::string flag = "is_saved_as_half_float";
    const std::size_t secondFlag = bytes.find(flag, bytes.find("Tree_float_5_4_3", bytes.find("Tree_float_5_4_3") + 1));
    ASSERT_NE(secondFlag, std::string::npos);
    const std::size_t valueAt = secondFlag + flag.size() + 4 + 4 + 4;
    ASSERT_EQ(bytes.substr(valueAt - 8, 4), "bool");
    std::string badFlag = bytes;
    badFlag[valueAt] = 'y';
    EXPECT_NE(openMessage(file, badFlag, "density").find(file + ": damaged VDB file: a bool metadata value at byte " +
                                                          std::to_string(valueAt) + " is neither 0 nor 1"),
        std::string::npos)
        << openMessage(file, badFlag, "density");

    // The second grid's buffers cut short: found by walking past the first grid's data, whose
    // end is not written down.
    std::string truncated = bytes.substr(0, bytes.size() - 100);
    EXPECT_NE(openMessage(file, truncated, "density").find(file + ": damaged VDB file: "), std::string::npos)
        << openMessage(file, truncated, "density");
}

TEST(GridSource, TransformedMovesTheGridAndTheGridsAttachedBeforeOrAfterFromFilesOrHosts)
{
    // A lumpy density and a flame grid, moved by a rotation, a non-uniform scale, a shear and a
    // translation (a DCC object's transform), against the same grids written with the moved map.
    TempDir dir;
    const auto lumpy = [](const openvdb::Coord& c) { return 0.2f + 0.1f * float((c.x() * 7 + c.y() * 3 + c.z()) % 5); };
    auto density = makeFogGrid(openvdb::Coord(0), openvdb::Coord(11, 7, 9), lumpy, 0.1);
    auto flame = makeFogGrid(openvdb::Coord(3), openvdb::Coord(8, 5, 7), [](const openvdb::Coord& c) { return 0.5f + 0.1f * float(c.x()); }, 0.1);
    flame->setName("flame");
    const std::string original = dir.file("original.vdb"), premoved = dir.file("moved.vdb");
    {
        openvdb::io::File file(original);
        file.write({density, flame});
    }
    const openvdb::GridBase::Ptr hostFlame = flame->deepCopy(); // a host's grid, in the file's world
    Mat4d m(1.0); // columns
    const double a = 0.5;
    m[0] = glm::dvec4(2.0 * std::cos(a), 0.0, -2.0 * std::sin(a), 0.0); // x scaled 2, rotated about y
    m[1] = glm::dvec4(0.3, 1.0, 0.0, 0.0);                             // y sheared into x
    m[2] = glm::dvec4(0.5 * std::sin(a), 0.0, 0.5 * std::cos(a), 0.0); // z scaled 0.5
    m[3] = glm::dvec4(1.0, 2.0, 3.0, 1.0);
    openvdb::Mat4d composite = density->transform().baseMap()->getAffineMap()->getMat4(); // row vectors
    openvdb::Mat4d rowM;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) rowM(r, c) = m[r][c];
    composite = composite * rowM; // index -> file world -> moved world
    for (auto grid : {density, flame}) grid->setTransform(openvdb::math::Transform::createLinearTransform(composite));
    {
        openvdb::io::File file(premoved);
        file.write({density, flame});
    }

    const GridSource expected = GridSource::open(premoved).withEmissionGrid("flame");
    const GridSource movedThenAttached = GridSource::open(original).transformed(m).withEmissionGrid("flame");
    const GridSource attachedThenMoved = GridSource::open(original).withEmissionGrid("flame").transformed(m);
    const GridSource hostAttachedAfter = withEmissionGrid(GridSource::open(original).transformed(m), hostFlame);
    const Vec3d c0 = GridSource::open(original).worldCentre();
    const Vec3d c1 = Vec3d(m * glm::dvec4(c0, 1.0));
    for (const GridSource* g : {&movedThenAttached, &attachedThenMoved}) {
        EXPECT_NEAR(glm::length(g->worldCentre() - c1), 0.0, 1e-9);
        EXPECT_NEAR(glm::length(g->worldCentre() - expected.worldCentre()), 0.0, 1e-9);
    }
    RenderSettings rs;
    const Camera camera(lookAtCamera(c1 + Vec3d(0.5, 1.0, 4.0), c1, 96, 64), c1);
    const Image want = Renderer(rs).render(expected, camera);
    ASSERT_GT(alphaSum(want), 50.0);
    EXPECT_LT(maxAbsDiff(Renderer(rs).render(movedThenAttached, camera), want), 1e-4);
    EXPECT_LT(maxAbsDiff(Renderer(rs).render(attachedThenMoved, camera), want), 1e-4);
    EXPECT_LT(maxAbsDiff(Renderer(rs).render(hostAttachedAfter, camera), want), 1e-4);
    // Unmoved, the image is another.
    EXPECT_GT(maxAbsDiff(Renderer(rs).render(GridSource::open(original).withEmissionGrid("flame"), camera), want), 0.1);

    Mat4d projective = m;
    projective[0][3] = 0.1;
    EXPECT_NE(messageOf<ValueError>([&] { GridSource::open(original).transformed(projective); }).find("last row must be 0, 0, 0, 1"),
        std::string::npos);
    Mat4d flat = m;
    flat[2] = glm::dvec4(0.0);
    EXPECT_NE(messageOf<ValueError>([&] { GridSource::open(original).transformed(flat); }).find("singular"), std::string::npos);
}
