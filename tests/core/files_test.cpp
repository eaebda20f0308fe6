// core/files.h: what a command may read and write, refused before any work with the file named.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "bounce/core/error.h"
#include "bounce/core/files.h"

namespace bounce {
namespace {

namespace fs = std::filesystem;

struct FilesTest : ::testing::Test {
    fs::path dir = fs::temp_directory_path() / ("bounce-files-test-" + std::to_string(::getpid()));
    void SetUp() override {
        fs::create_directories(dir / "sub");
        std::ofstream(dir / "in.json") << "{}";
    }
    void TearDown() override { fs::remove_all(dir); }
    std::string refusal(const std::string& out, const std::vector<std::string>& inputs, const std::vector<std::string>& folders = {}) {
        try {
            check_output_file(out, inputs, folders);
        } catch (const InputError& e) {
            return e.what();
        }
        return "";
    }
};

TEST_F(FilesTest, OutputsThatWouldDestroyAnInputAreRefused) {
    const std::string in = (dir / "in.json").string();
    EXPECT_EQ(refusal((dir / "out.exr").string(), {in}), "");  // a new name
    EXPECT_NE(refusal(in, {in}).find(in), std::string::npos);
    // The same file by another spelling.
    EXPECT_NE(refusal((dir / "sub" / ".." / "in.json").string(), {in}), "");
    EXPECT_NE(refusal((dir / "sub").string(), {}), "");                                      // a directory
    EXPECT_NE(refusal("/dev/null", {}), "");                                                 // a device
    EXPECT_NE(refusal((dir / "nowhere" / "x.exr").string(), {}), "");                        // no such folder
    EXPECT_NE(refusal((dir / "sub" / "x.exr").string(), {}, {(dir / "sub").string()}), "");  // inside a folder it reads
    EXPECT_EQ(not_a_regular_file(in), "");
    EXPECT_NE(not_a_regular_file((dir / "sub").string()), "");
    EXPECT_THROW(check_input_file((dir / "missing.json").string()), InputError);
}

TEST_F(FilesTest, ExtensionsAndContentHashes) {
    EXPECT_EQ(lower_extension("a/B.PLY"), ".ply");
    EXPECT_EQ(lower_extension("noext"), "");
    EXPECT_EQ(ascii_lower("HeLLo"), "hello");
    EXPECT_TRUE(inside(dir / "sub" / "x", dir));
    EXPECT_FALSE(inside(dir, dir / "sub"));
    const std::string in = (dir / "in.json").string();
    const uint64_t h = file_content_hash(in);
    EXPECT_NE(h, 0u);
    FileHashes remembered;
    EXPECT_EQ(remembered.hash(in), h);
    std::ofstream(in) << "{\"changed\": 1}";
    EXPECT_NE(file_content_hash(in), h);
    EXPECT_EQ(file_content_hash((dir / "missing").string()), 0u);
}

}  // namespace
}  // namespace bounce
