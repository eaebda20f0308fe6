// scene/keyframes.h's keys_light, which the plan asks whether a shot's light changes (the keys'
// values themselves are tested with the shot, in tests/render/animation_test.cpp): a keyed light
// or material emission, and nothing else.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "bounce/scene/keyframes.h"

namespace bounce {
namespace {

using nlohmann::json;

TEST(Keyframes, KeysLightSeesAKeyedLightOrEmissionOnly) {
    const json keys = {{"keys", {{1, 1.0}, {2, 2.0}}}};
    EXPECT_TRUE(keys_light({{"lights", {{{"intensity", keys}}}}}));
    EXPECT_TRUE(keys_light({{"materials", {{"lamp", {{"emission", keys}}}}}}));
    EXPECT_FALSE(keys_light({{"materials", {{"wall", {{"color", keys}}}}}}));
    EXPECT_FALSE(keys_light({{"camera", {{"fov", keys}}}}));
    EXPECT_FALSE(keys_light(json()));
}

}  // namespace
}  // namespace bounce
