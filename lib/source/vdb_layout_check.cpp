/// @file vdb_layout_check.cpp
#include "source/vdb_layout_check.h"

#include <vdb_ewa/error.h>

#include "support/openvdb.h"

#include <cstdint>
#include <fstream>
#include <map>

namespace vdb_ewa {
namespace detail {
namespace {

/// A bounds-checked reader over the file: every read names what it reads.
class LayoutReader
{
public:
    explicit LayoutReader(const std::string& path) : mPath(path), mIn(path, std::ios::binary)
    {
        mIn.seekg(0, std::ios::end);
        mSize = std::uint64_t(std::max<std::streamoff>(mIn.tellg(), 0));
        mIn.seekg(0);
    }

    std::uint64_t size() const { return mSize; }
    std::uint64_t position() const { return mPos; }

    [[noreturn]] void fail(const std::string& what) const
    {
        throw IoError(mPath + ": damaged VDB file: " + what + " (the file has " + std::to_string(mSize) + " bytes)");
    }

    /// Skip @a bytes of @a what.
    void skip(std::uint64_t bytes, const char* what)
    {
        if (bytes > mSize - mPos) fail(std::string(what) + " at byte " + std::to_string(mPos) + " needs " + std::to_string(bytes) + " bytes");
        mPos += bytes;
        mIn.seekg(std::streamoff(mPos));
    }

    template <typename T>
    T read(const char* what)
    {
        T value{};
        const std::uint64_t at = mPos;
        skip(sizeof(T), what);
        mIn.seekg(std::streamoff(at));
        mIn.read(reinterpret_cast<char*>(&value), sizeof(T));
        if (!mIn) fail(std::string("cannot read ") + what + " at byte " + std::to_string(at));
        return value;
    }

    /// An OpenVDB string: a 32-bit length, then that many bytes (skipped unless @a keep).
    std::string string(const char* what, bool keep = false)
    {
        const std::uint64_t at = mPos;
        const std::uint32_t length = read<std::uint32_t>(what);
        if (length > mSize - mPos) {
            fail(std::string(what) + " at byte " + std::to_string(at) + " claims " + std::to_string(length) + " bytes");
        }
        std::string text;
        if (keep) {
            text.resize(length);
            mIn.read(text.data(), std::streamsize(length));
        }
        skip(length, what);
        return text;
    }

    void seek(std::uint64_t position, const char* what)
    {
        if (position > mSize) fail(std::string(what) + " " + std::to_string(position) + " lies past the end");
        mPos = position;
        mIn.seekg(std::streamoff(mPos));
    }

    /// A MetaMap: a count, then (name, type name, 32-bit byte count, bytes) per entry.
    void metaMap(const char* what)
    {
        const std::uint64_t at = mPos;
        const std::uint32_t count = read<std::uint32_t>(what);
        if (count > (mSize - mPos) / 12) {
            fail(std::string(what) + " at byte " + std::to_string(at) + " claims " + std::to_string(count) + " entries");
        }
        for (std::uint32_t i = 0; i < count; ++i) {
            string("metadata name");
            string("metadata type");
            const std::uint64_t valueAt = mPos;
            const std::uint32_t bytes = read<std::uint32_t>("metadata value size");
            if (bytes > mSize - mPos) fail("a metadata value at byte " + std::to_string(valueAt) + " claims " + std::to_string(bytes) + " bytes");
            skip(bytes, "metadata value");
        }
    }

private:
    std::string mPath;
    std::ifstream mIn;
    std::uint64_t mSize = 0, mPos = 0;
};

/// OpenVDB's map types and the bytes of their data (0: not walked further).
const std::map<std::string, std::uint64_t> kMapBytes = {{"AffineMap", 128}, {"UnitaryMap", 128}, {"ScaleMap", 120},
    {"UniformScaleMap", 120}, {"TranslationMap", 24}, {"ScaleTranslateMap", 144}, {"UniformScaleTranslateMap", 144},
    {"NonlinearFrustumMap", 0}};

/// Bytes of a tree's value type from its grid type name ("Tree_float_5_4_3"); 0 if unknown.
std::uint64_t valueBytes(const std::string& type)
{
    for (const auto& [name, bytes] : std::map<std::string, std::uint64_t>{{"_float_", 4}, {"_double_", 8}, {"_int32_", 4},
             {"_int64_", 8}, {"_vec3s_", 12}, {"_vec3d_", 24}, {"_vec3i_", 12}, {"_bool_", 1}}) {
        if (type.rfind("Tree" + name, 0) == 0) return bytes;
    }
    return 0;
}

} // namespace

void checkVdbLayout(const std::string& path)
{
    LayoutReader in(path);
    if (in.size() < 8) in.fail("shorter than a VDB header");
    if (in.read<std::int64_t>("magic number") != openvdb::OPENVDB_MAGIC) return; // OpenVDB says "not a VDB file"
    std::uint32_t version = in.read<std::uint32_t>("file format version");
    if (version < 211) {
        in.skip(8, "file format minor and patch versions");
        return; // too old to walk further: left to OpenVDB
    }
    in.skip(8, "library version");
    bool offsets = true;
    if (version >= 212) offsets = in.read<char>("grid offsets flag") != 0;
    if (version >= openvdb::OPENVDB_FILE_VERSION_SELECTIVE_COMPRESSION &&
        version < openvdb::OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION) {
        in.skip(1, "compression flag");
    }
    in.skip(version >= openvdb::OPENVDB_FILE_VERSION_BOOST_UUID ? 36 : 16, "file UUID");
    in.metaMap("file metadata");
    const std::uint64_t countAt = in.position();
    const std::int32_t grids = in.read<std::int32_t>("grid count");
    if (grids < 0 || std::uint64_t(grids) > (in.size() - in.position()) / 36) {
        in.fail("the grid count at byte " + std::to_string(countAt) + " claims " + std::to_string(grids) + " grids");
    }
    if (!offsets) return; // a stream without offsets: grids follow one another, left to OpenVDB
    for (std::int32_t g = 0; g < grids; ++g) {
        in.string("grid name");
        const std::string type = in.string("grid type", true);
        if (version >= openvdb::OPENVDB_FILE_VERSION_GRID_INSTANCING) in.string("instance parent name");
        const std::uint64_t descriptorEnd = in.position() + 24;
        const std::int64_t gridPos = in.read<std::int64_t>("grid offset"), blockPos = in.read<std::int64_t>("data offset"),
                           endPos = in.read<std::int64_t>("grid end offset");
        if (gridPos < std::int64_t(descriptorEnd) || blockPos < gridPos || endPos < blockPos || std::uint64_t(endPos) > in.size()) {
            in.fail("grid " + std::to_string(g) + "'s offsets " + std::to_string(gridPos) + ", " + std::to_string(blockPos) + ", " +
                    std::to_string(endPos) + " are out of order or past the end");
        }
        in.seek(std::uint64_t(gridPos), "grid offset");
        if (version >= openvdb::OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION) in.skip(4, "grid compression flags");
        in.metaMap("grid metadata");
        if (version >= openvdb::OPENVDB_FILE_VERSION_GRID_INSTANCING) {
            const std::uint64_t at = in.position();
            const std::string map = in.string("transform type", true);
            const auto known = kMapBytes.find(map);
            if (known == kMapBytes.end()) in.fail("the transform type at byte " + std::to_string(at) + " is not a map OpenVDB knows");
            // The root node's tile and child counts: OpenVDB reads 2^31 tiles one by one (34 s).
            const std::uint64_t value = valueBytes(type);
            if (known->second > 0 && value > 0 && version >= openvdb::OPENVDB_FILE_VERSION_ROOTNODE_MAP) {
                in.skip(known->second, "transform");
                if (in.read<std::int32_t>("tree buffer count") == 1) {
                    in.skip(value, "background value");
                    const std::uint64_t countsAt = in.position();
                    const std::uint64_t tiles = in.read<std::uint32_t>("root tile count"),
                                        children = in.read<std::uint32_t>("root child count");
                    const std::uint64_t room = std::uint64_t(blockPos) - std::min<std::uint64_t>(in.position(), std::uint64_t(blockPos));
                    if (tiles * (13 + value) + children * 12 > room) {
                        in.fail("the root node at byte " + std::to_string(countsAt) + " claims " + std::to_string(tiles) + " tiles and " +
                                std::to_string(children) + " children in " + std::to_string(room) + " bytes of topology");
                    }
                }
            }
        }
        if (in.position() > std::uint64_t(blockPos)) in.fail("grid " + std::to_string(g) + "'s header runs into its data");
        in.seek(std::uint64_t(endPos), "grid end offset");
    }
}

} // namespace detail
} // namespace vdb_ewa
