// core/error.h: an input error is one line naming the file and the place, and "did you mean"
// finds the nearest candidate within a small edit distance, and none beyond it.
#include <gtest/gtest.h>

#include "bounce/core/error.h"

namespace bounce {
namespace {

TEST(Error, AnInputErrorIsOneLineNamingTheFileAndThePlace) {
    const InputError e("scene.json", "/lights/0/intensity", "expected a number,\ngot a string\r\n");
    EXPECT_STREQ(e.what(), "scene.json: /lights/0/intensity: error: expected a number, got a string");
    EXPECT_EQ(e.file(), "scene.json");
    EXPECT_EQ(e.place(), "/lights/0/intensity");
    EXPECT_STREQ(InputError("f.obj", "", "bad").what(), "f.obj: error: bad");
    EXPECT_STREQ(InputError("", "", "bad").what(), "error: bad");
}

TEST(Error, DidYouMeanFindsTheNearestCandidate) {
    EXPECT_EQ(closest_match("min_spacng", {"min_spacing", "max_spacing", "rays"}), "min_spacing");
    EXPECT_EQ(closest_match("rayz", std::vector<std::string>{"rays", "spp"}), "rays");
    EXPECT_EQ(closest_match("photons", {"rays", "spp"}), "");
}

}  // namespace
}  // namespace bounce
