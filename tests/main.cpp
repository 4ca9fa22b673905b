/// @file main.cpp
/// @brief Test runner: initialises OpenVDB once; `--threads N` limits TBB (tests only).
#include <gtest/gtest.h>

#include <openvdb/openvdb.h>
#include <tbb/global_control.h>

#include <cstdlib>
#include <cstring>
#include <memory>

int main(int argc, char** argv)
{
    ::testing::InitGoogleTest(&argc, argv);
    std::unique_ptr<tbb::global_control> limit;
    for (int i = 1; i + 1 < argc; ++i) {
        if (std::strcmp(argv[i], "--threads") == 0) {
            limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                std::size_t(std::atoi(argv[i + 1])));
        }
    }
    openvdb::initialize();
    return RUN_ALL_TESTS();
}
