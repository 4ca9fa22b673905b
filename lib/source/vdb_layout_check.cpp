/// @file vdb_layout_check.cpp
#include "source/vdb_layout_check.h"

#include <vdb_ewa/error.h>

#include "support/openvdb.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <map>
#include <vector>

namespace vdb_ewa {
namespace detail {
namespace {

/// The bytes TypedMetadata<T>::readValue reads for the metadata types openvdb::initialize()
/// registers with a fixed size (MetaTypes, ptidx32/64); strings and delayed-load metadata
/// read their stored size.
const std::map<std::string, std::uint32_t> kFixedMetadataBytes = {{"bool", 1}, {"float", 4}, {"double", 8}, {"int32", 4},
    {"int64", 8}, {"ptidx32", 4}, {"ptidx64", 8}, {"vec2i", 8}, {"vec2s", 8}, {"vec2d", 16}, {"vec3i", 12}, {"vec3s", 12},
    {"vec3d", 24}, {"vec4i", 16}, {"vec4s", 16}, {"vec4d", 32}, {"mat4s", 64}, {"mat4d", 128}};

/// A bounds-checked reader over the file: every read names what it reads. Reads go through a
/// 64 KB window filled by pread(2), so the walk costs a system call a window, not two a field.
class LayoutReader
{
public:
    explicit LayoutReader(const std::string& path) : mPath(path), mFd(::open(path.c_str(), O_RDONLY | O_CLOEXEC))
    {
        struct stat st {};
        if (mFd >= 0 && ::fstat(mFd, &st) == 0) mSize = std::uint64_t(std::max<off_t>(st.st_size, 0));
    }
    ~LayoutReader()
    {
        if (mFd >= 0) ::close(mFd);
    }
    LayoutReader(const LayoutReader&) = delete;
    LayoutReader& operator=(const LayoutReader&) = delete;

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
    }

    template <typename T>
    T read(const char* what)
    {
        T value{};
        bytes(&value, sizeof(T), what);
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
            bytes(text.data(), length, what);
        } else {
            skip(length, what);
        }
        return text;
    }

    /// Read @a count bytes of @a what into @a out.
    void bytes(void* out, std::uint64_t count, const char* what)
    {
        const std::uint64_t at = mPos;
        skip(count, what);
        char* dst = static_cast<char*>(out);
        for (std::uint64_t done = 0; done < count;) {
            const std::uint64_t from = at + done;
            if (from < mWindowAt || from >= mWindowAt + mWindowBytes) {
                const ssize_t got = ::pread(mFd, mWindow.data(), mWindow.size(), off_t(from));
                if (got <= 0) fail(std::string("cannot read ") + what + " at byte " + std::to_string(at));
                mWindowAt = from;
                mWindowBytes = std::uint64_t(got);
            }
            const std::uint64_t n = std::min(count - done, mWindowAt + mWindowBytes - from);
            std::memcpy(dst + done, mWindow.data() + (from - mWindowAt), n);
            done += n;
        }
    }

    void seek(std::uint64_t position, const char* what)
    {
        if (position > mSize) fail(std::string(what) + " " + std::to_string(position) + " lies past the end");
        mPos = position;
    }

    /// A MetaMap (MetaMap::readMeta): a count, then (name, type name, 32-bit byte count, bytes)
    /// per entry. Returns GridBase::saveFloatAsHalf() of the map read: the last
    /// "is_saved_as_half_float" entry, 0 or 1 for a bool, -1 (unknown) for another type.
    int metaMap(const char* what)
    {
        const std::uint64_t at = mPos;
        const std::uint32_t count = read<std::uint32_t>(what);
        if (count > (mSize - mPos) / 12) {
            fail(std::string(what) + " at byte " + std::to_string(at) + " claims " + std::to_string(count) + " entries");
        }
        int half = 0;
        for (std::uint32_t i = 0; i < count; ++i) {
            const bool halfFlag = string("metadata name", true) == "is_saved_as_half_float";
            const std::string type = string("metadata type", true);
            const std::uint64_t valueAt = mPos;
            const std::uint32_t bytes = read<std::uint32_t>("metadata value size");
            if (bytes > mSize - mPos) fail("a metadata value at byte " + std::to_string(valueAt) + " claims " + std::to_string(bytes) + " bytes");
            // TypedMetadata::readValue reads sizeof(T) whatever the size says: another size
            // would put OpenVDB's next read elsewhere than this walk's.
            const auto fixed = kFixedMetadataBytes.find(type);
            if (fixed != kFixedMetadataBytes.end() && bytes != fixed->second) {
                fail("a " + type + " metadata value at byte " + std::to_string(valueAt) + " claims " + std::to_string(bytes) +
                     " bytes, not " + std::to_string(fixed->second));
            }
            const std::uint64_t end = mPos + bytes;
            if (type == "__delayedload" && bytes > 0) delayedLoadMetadata(end);
            if (type == "bool") {
                const auto value = read<std::uint8_t>("bool metadata");
                if (value > 1) fail("a bool metadata value at byte " + std::to_string(valueAt + 4) + " is neither 0 nor 1"); // UB as a bool
                if (halfFlag) half = value;
            } else if (halfFlag) {
                half = -1; // Metadata::asBool of another type: left to OpenVDB
            }
            seek(end, "metadata value end");
        }
        return half;
    }

    /// OpenVDB's delayed-load metadata (io::DelayedLoadMetadata::readValue), ending at @a end:
    /// a leaf count, then a mask of one byte a leaf and the leaves' compressed sizes (8 bytes
    /// each), each raw or blosc-compressed behind a 32-bit byte count. OpenVDB allocates all
    /// three by what the file says: a count or a blosc header of 2^32 took 4 GB.
    void delayedLoadMetadata(std::uint64_t end)
    {
        const std::uint64_t at = mPos;
        const std::uint64_t leaves = read<std::uint32_t>("delayed-load leaf count");
        // Every leaf takes at least a byte of the file, so a larger count is damage.
        if (leaves > mSize) fail("the delayed-load metadata at byte " + std::to_string(at) + " claims " + std::to_string(leaves) + " leaves");
        for (const std::uint64_t itemBytes : {std::uint64_t(1), std::uint64_t(8)}) {
            const std::uint64_t blockAt = mPos;
            const std::uint32_t bytes = read<std::uint32_t>("delayed-load block size");
            if (itemBytes == 8 && bytes == 0xffffffffu) break; // no compressed sizes stored
            if (bytes > 0 && bytes < 16) fail("the delayed-load metadata block at byte " + std::to_string(blockAt) + " is shorter than a blosc header");
            const std::uint64_t stored = bytes > 0 ? bytes : leaves * itemBytes;
            if (stored > end - std::min(end, mPos)) {
                fail("the delayed-load metadata block at byte " + std::to_string(blockAt) + " claims " + std::to_string(stored) + " bytes");
            }
            if (bytes >= 16) {
                const std::uint64_t unpacked = bloscHeader(blockAt, bytes);
                // OpenVDB's bloscCompress pads inputs shorter than 128 bytes to 128.
                if (unpacked > std::max<std::uint64_t>(leaves * itemBytes, 128) + 64) {
                    fail("the delayed-load metadata block at byte " + std::to_string(blockAt) + " unpacks to " + std::to_string(unpacked) +
                         " bytes for " + std::to_string(leaves) + " leaves");
                }
                skip(stored - 16, "delayed-load block");
            } else {
                skip(stored, "delayed-load block");
            }
        }
    }

    /// The 16-byte blosc header of a block of @a stored bytes (at byte @a at) that OpenVDB hands
    /// to blosc_decompress_ctx, which takes the block's length from the header: a length other
    /// than @a stored would read past the block OpenVDB allocated. Returns the unpacked size.
    std::uint64_t bloscHeader(std::uint64_t at, std::uint64_t stored)
    {
        std::uint32_t header[4];
        bytes(header, sizeof header, "blosc header");
        if (header[3] != stored) {
            fail("the blosc block at byte " + std::to_string(at) + " holds " + std::to_string(stored) + " bytes, its header says " +
                 std::to_string(header[3]));
        }
        return header[1];
    }

private:
    std::string mPath;
    int mFd;
    std::uint64_t mSize = 0, mPos = 0;
    std::array<char, 65536> mWindow{};
    std::uint64_t mWindowAt = 0, mWindowBytes = 0;
};

/// OpenVDB's map types and the bytes of their data (0: not walked further).
const std::map<std::string, std::uint64_t> kMapBytes = {{"AffineMap", 128}, {"UnitaryMap", 128}, {"ScaleMap", 120},
    {"UniformScaleMap", 120}, {"TranslationMap", 24}, {"ScaleTranslateMap", 144}, {"UniformScaleTranslateMap", 144},
    {"NonlinearFrustumMap", 0}};

/// A tree's value type, from its grid type name ("Tree_float_5_4_3"; GridDescriptor::read drops
/// a "_HalfFloat" suffix): bytes in memory, components, whether half applies (RealToHalf and
/// the grid metadata's is_saved_as_half_float, as GridBase::saveFloatAsHalf), and whether the
/// tree is one whose nodes are walked (5_4_3 trees of non-bool values, the half flag known).
struct TreeType
{
    std::uint64_t valueBytes = 0; ///< 0: unknown, not walked below the root's counts
    std::uint64_t components = 1;
    bool real = false;
    bool walked = false;
    bool half = false;

    TreeType(const std::string& type, int savedAsHalf)
    {
        struct Known { const char* name; std::uint64_t bytes, components; bool real; };
        for (const Known& k : {Known{"_float_", 4, 1, true}, Known{"_double_", 8, 1, true}, Known{"_int32_", 4, 1, false},
                 Known{"_int64_", 8, 1, false}, Known{"_vec3s_", 12, 3, true}, Known{"_vec3d_", 24, 3, true},
                 Known{"_vec3i_", 12, 3, false}, Known{"_bool_", 1, 1, false}}) {
            if (type.rfind(std::string("Tree") + k.name, 0) != 0) continue;
            valueBytes = k.bytes;
            components = k.components;
            real = k.real;
            const std::string rest = type.substr(4 + std::strlen(k.name));
            half = real && savedAsHalf == 1;
            walked = std::string(k.name) != "_bool_" && (rest == "5_4_3" || rest == "5_4_3_HalfFloat") && savedAsHalf >= 0;
        }
    }
    /// Bytes of a value as stored in node buffers.
    std::uint64_t storedBytes() const { return half ? 2 * components : valueBytes; }
};

/// Walks a 5-4-3 tree's topology and buffers the way OpenVDB 10 reads them (RootNode,
/// InternalNode and LeafNode readTopology and readBuffers, io::readCompressedValues), each
/// count, mask and block size against the bytes left. Masks are read whole; compressed blocks
/// are seeked over, never decompressed.
class TreeWalk
{
public:
    TreeWalk(LayoutReader& in, const TreeType& type, std::uint32_t compression) : mIn(in), mType(type), mCompression(compression) {}

    /// The topology, which must end by @a end (the grid's data offset); below the root's counts
    /// only when @a deep.
    void topology(std::uint64_t end, bool deep)
    {
        mIn.skip(mType.valueBytes, "background value");
        const std::uint64_t countsAt = mIn.position();
        const std::uint64_t tiles = mIn.read<std::uint32_t>("root tile count"), children = mIn.read<std::uint32_t>("root child count");
        const std::uint64_t room = end - std::min(end, mIn.position());
        // OpenVDB reads 2^31 tiles one by one (34 s); a child is at least its origin (and masks).
        if (tiles * (13 + mType.valueBytes) + children * (12 + (deep ? 2 * kMaskBytes[0] : 0)) > room) {
            mIn.fail("the root node at byte " + std::to_string(countsAt) + " claims " + std::to_string(tiles) + " tiles and " +
                     std::to_string(children) + " children in " + std::to_string(room) + " bytes of topology");
        }
        if (!deep) return;
        for (std::uint64_t t = 0; t < tiles; ++t) { // origin, value, active flag (a bool: 0 or 1)
            mIn.skip(12 + mType.valueBytes, "root tile");
            const auto active = mIn.read<std::uint8_t>("root tile active flag");
            if (active > 1) mIn.fail("a root tile's active flag at byte " + std::to_string(mIn.position() - 1) + " is " + std::to_string(active));
        }
        for (std::uint64_t c = 0; c < children; ++c) {
            Child child;
            mIn.bytes(child.origin.data(), 12, "root child origin");
            child.firstLeaf = mLeafActive.size();
            internalTopology(0);
            child.leaves = mLeafActive.size() - child.firstLeaf;
            mChildren[child.origin] = child; // a repeated origin replaces the earlier child, as in RootNode's table
            if (mIn.position() > end) mIn.fail("the tree's topology runs past its data offset " + std::to_string(end));
        }
    }

    /// The leaf buffers, from @a begin (the grid's data offset) to at most @a end, in the order
    /// RootNode::readBuffers visits them (its table: root children sorted by origin). OpenVDB
    /// reads them straight after the topology (Archive's doReadGrid), so that must end at @a begin.
    void buffers(std::uint64_t begin, std::uint64_t end)
    {
        if (mIn.position() != begin) {
            mIn.fail("the tree's topology ends at byte " + std::to_string(mIn.position()) + ", not at its data offset " + std::to_string(begin));
        }
        for (const auto& [origin, child] : mChildren) {
            for (std::uint64_t leaf = child.firstLeaf; leaf < child.firstLeaf + child.leaves; ++leaf) {
                std::uint64_t mask[8];
                mIn.bytes(mask, sizeof mask, "leaf value mask");
                if (countOn(mask, 8) != mLeafActive[leaf]) {
                    mIn.fail("a leaf's value mask at byte " + std::to_string(mIn.position() - 64) + " differs from the tree's topology");
                }
                compressedValues(512, mLeafActive[leaf]);
            }
        }
        if (mIn.position() > end) mIn.fail("the tree's data runs past its end offset " + std::to_string(end));
    }

private:
    static constexpr std::uint64_t kMaskBytes[3] = {4096, 512, 64}; ///< 32^3, 16^3 and 8^3 bits
    static constexpr std::uint64_t kNodeValues[3] = {32768, 4096, 512};

    struct Child
    {
        std::array<std::int32_t, 3> origin{};
        std::uint64_t firstLeaf = 0, leaves = 0;
    };

    static std::uint64_t countOn(const std::uint64_t* words, std::size_t n)
    {
        std::uint64_t on = 0;
        for (std::size_t i = 0; i < n; ++i) on += std::uint64_t(__builtin_popcountll(words[i]));
        return on;
    }

    /// InternalNode::readTopology at @a level (0: 32^3, 1: 16^3), then its children.
    void internalTopology(int level)
    {
        std::vector<std::uint64_t> childMask(kMaskBytes[level] / 8), valueMask(kMaskBytes[level] / 8);
        mIn.bytes(childMask.data(), kMaskBytes[level], "child mask");
        mIn.bytes(valueMask.data(), kMaskBytes[level], "value mask");
        compressedValues(kNodeValues[level], countOn(valueMask.data(), valueMask.size()));
        const std::uint64_t children = countOn(childMask.data(), childMask.size());
        if (children * kMaskBytes[level + 1] > mIn.size() - mIn.position()) {
            mIn.fail("a node at byte " + std::to_string(mIn.position()) + " claims " + std::to_string(children) + " children");
        }
        for (std::uint64_t c = 0; c < children; ++c) {
            if (level == 1) { // LeafNode::readTopology: its value mask
                std::uint64_t mask[8];
                mIn.bytes(mask, sizeof mask, "leaf value mask");
                mLeafActive.push_back(std::uint16_t(countOn(mask, 8)));
            } else {
                internalTopology(level + 1);
            }
        }
    }

    /// io::readCompressedValues of a node of @a values values, @a active of them active.
    void compressedValues(std::uint64_t values, std::uint64_t active)
    {
        const std::uint64_t at = mIn.position();
        const auto metadata = mIn.read<std::uint8_t>("node compression metadata");
        if (metadata > 6) mIn.fail("the node compression metadata at byte " + std::to_string(at) + " is " + std::to_string(metadata));
        // 2, 4, 5: one or two inactive values; 3, 4, 5: a selection mask; 6: all values.
        if (metadata == 2 || metadata == 4 || metadata == 5) mIn.skip(mType.valueBytes * (metadata == 5 ? 2 : 1), "inactive values");
        if (metadata >= 3 && metadata <= 5) mIn.skip(values / 8, "selection mask");
        const bool maskCompressed = (mCompression & 0x2) != 0;
        const std::uint64_t count = maskCompressed && metadata != 6 ? active : values;
        const std::uint64_t bytes = count * mType.storedBytes();
        if (mType.half && count == 0) return; // HalfReader::read reads nothing for no values
        if ((mCompression & 0x5) == 0) { // neither blosc (4) nor zip (1): raw values
            mIn.skip(bytes, "node values");
            return;
        }
        // zipFromStream / bloscFromStream: a signed byte count; <= 0 means raw.
        const std::uint64_t sizeAt = mIn.position();
        const std::int64_t stored = mIn.read<std::int64_t>("compressed block size");
        if (stored <= 0 && std::uint64_t(-stored) != bytes) {
            mIn.fail("the raw block at byte " + std::to_string(sizeAt) + " holds " + std::to_string(-stored) + " bytes for " +
                     std::to_string(bytes) + " bytes of values");
        }
        const std::uint64_t length = stored <= 0 ? bytes : std::uint64_t(stored);
        if (length > mIn.size() - mIn.position()) {
            mIn.fail("the compressed block at byte " + std::to_string(sizeAt) + " claims " + std::to_string(length) + " bytes");
        }
        if (stored > 0 && (mCompression & 0x4) != 0) { // bloscFromStream: blosc_decompress_ctx
            if (stored < 16) mIn.fail("the blosc block at byte " + std::to_string(sizeAt) + " is shorter than a blosc header");
            const std::uint64_t unpacked = mIn.bloscHeader(sizeAt, length);
            if (unpacked != bytes) {
                mIn.fail("the blosc block at byte " + std::to_string(sizeAt) + " unpacks to " + std::to_string(unpacked) + " bytes for " +
                         std::to_string(bytes) + " bytes of values");
            }
            mIn.skip(length - 16, "compressed block");
            return;
        }
        mIn.skip(length, "compressed block");
    }

    LayoutReader& mIn;
    TreeType mType;
    std::uint32_t mCompression;
    std::vector<std::uint16_t> mLeafActive; ///< active voxels of each leaf, in topology order
    std::map<std::array<std::int32_t, 3>, Child> mChildren;
};

} // namespace

void checkVdbLayout(const std::string& path)
{
    LayoutReader in(path);
    if (in.size() < 8) in.fail("shorter than a VDB header");
    if (in.read<std::int64_t>("magic number") != openvdb::OPENVDB_MAGIC) return; // OpenVDB says "not a VDB file"
    const std::uint32_t version = in.read<std::uint32_t>("file format version");
    // Older formats (OpenVDB before 2.0, 2013) have no per-grid compression flags nor node
    // mask compression and are not walked; left to OpenVDB, a damaged one read for 10 s and
    // 3.4 GB (a fuzzing finding, version 0). Refused instead: no current tool writes them.
    if (version < openvdb::OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION) {
        throw IoError(path + ": VDB file format version " + std::to_string(version) + " is older than OpenVDB 2.0's (" +
                      std::to_string(openvdb::OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION) +
                      ") and is not read; re-save it with OpenVDB 2.0 or later");
    }
    in.skip(8, "library version");
    const bool offsets = in.read<char>("grid offsets flag") != 0;
    in.skip(36, "file UUID");
    in.metaMap("file metadata");
    const std::uint64_t countAt = in.position();
    const std::int32_t grids = in.read<std::int32_t>("grid count");
    if (grids < 0 || std::uint64_t(grids) > (in.size() - in.position()) / 36) {
        in.fail("the grid count at byte " + std::to_string(countAt) + " claims " + std::to_string(grids) + " grids");
    }
    // Without offsets (io::Stream's layout) File::open streams every grid in: each follows its
    // descriptor, its data follows its topology, and the next grid follows its data. The walk
    // follows as far as it can place the next grid; past a tree it does not walk, the rest is
    // left to OpenVDB.
    for (std::int32_t g = 0; g < grids; ++g) {
        in.string("grid name");
        const std::string type = in.string("grid type", true);
        // An instance shares its parent's tree: Archive::writeGridInstance writes no topology and
        // leaves the data offset 0, and Archive's doReadGrid reads no topology for it.
        const bool instance = !in.string("instance parent name", true).empty();
        const std::uint64_t descriptorEnd = in.position() + 24;
        const std::int64_t gridPos = in.read<std::int64_t>("grid offset"), storedBlockPos = in.read<std::int64_t>("data offset"),
                           endPos = in.read<std::int64_t>("grid end offset");
        const std::int64_t blockPos = instance ? endPos : storedBlockPos;
        if (offsets && (gridPos < std::int64_t(descriptorEnd) || blockPos < gridPos || endPos < blockPos || std::uint64_t(endPos) > in.size())) {
            in.fail("grid " + std::to_string(g) + "'s offsets " + std::to_string(gridPos) + ", " + std::to_string(storedBlockPos) + ", " +
                    std::to_string(endPos) + " are out of order or past the end");
        }
        if (offsets) in.seek(std::uint64_t(gridPos), "grid offset");
        // Where the topology must end and the data must: the offsets, else the file's end.
        const std::uint64_t dataBegin = offsets ? std::uint64_t(blockPos) : in.size(), dataEnd = offsets ? std::uint64_t(endPos) : in.size();
        const std::uint32_t compression = in.read<std::uint32_t>("grid compression flags");
        const int half = in.metaMap("grid metadata");
        { // the transform, then the tree
            const std::uint64_t at = in.position();
            const std::string map = in.string("transform type", true);
            const auto known = kMapBytes.find(map);
            if (known == kMapBytes.end()) in.fail("the transform type at byte " + std::to_string(at) + " is not a map OpenVDB knows");
            const TreeType tree(type, half);
            if (instance) {
                in.skip(known->second, "transform");
            } else if (known->second > 0 && tree.valueBytes > 0) {
                in.skip(known->second, "transform");
                in.skip(4, "tree buffer count"); // OpenVDB warns when it is not 1, and reads on
                // Below the root's counts only where the layout is the one walked here.
                const bool deep = tree.walked;
                TreeWalk walk(in, tree, compression);
                walk.topology(dataBegin, deep);
                if (!deep && !offsets) return;
                if (deep) {
                    walk.buffers(offsets ? dataBegin : in.position(), dataEnd);
                    if (offsets) in.seek(dataBegin, "data offset");
                }
            } else if (!offsets) {
                return;
            }
        }
        if (!offsets) continue; // the next grid follows
        if (in.position() > std::uint64_t(blockPos)) in.fail("grid " + std::to_string(g) + "'s header runs into its data");
        in.seek(std::uint64_t(endPos), "grid end offset");
    }
}

} // namespace detail
} // namespace vdb_ewa
