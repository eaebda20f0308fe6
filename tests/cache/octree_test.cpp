// cache/octree.h against a list: a lookup visits exactly the records whose support sphere holds
// the point (a record is stored in every node its box overlaps: none is missed where the walk
// goes down one path), each once, for records from far smaller than a node to larger than the
// scene; a copy answers the same.
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "bounce/cache/octree.h"
#include "bounce/core/random.h"

namespace bounce {
namespace {

TEST(RecordOctree, VisitsExactlyTheRecordsWhoseSupportHoldsThePointEachOnce) {
    const Bounds scene{{-10, -10, -10}, {10, 10, 10}};
    RecordOctree tree(scene);
    RandomStream rng(11, 12);
    struct R {
        Vec3 p;
        float support;
    };
    std::vector<R> records;
    const auto u = [&](uint64_t i, uint32_t d) { return rng.get(i, d); };
    for (uint64_t i = 0; i < 3000; ++i) {
        const Vec3 p{20 * u(i, 0) - 10, 20 * u(i, 1) - 10, 20 * u(i, 2) - 10};
        // Supports spread over five orders of magnitude: 0.001 to 100 (larger than the scene).
        const float support = 0.001f * std::pow(1e5f, u(i, 3));
        records.push_back({p, support});
        tree.insert(static_cast<uint32_t>(i), p, support);
    }
    const RecordOctree copy = tree;
    size_t hits = 0;
    for (uint64_t q = 0; q < 2000; ++q) {
        const Vec3 p{20 * u(q + 10000, 0) - 10, 20 * u(q + 10000, 1) - 10, 20 * u(q + 10000, 2) - 10};
        std::vector<uint32_t> want, got, got_copy;
        for (size_t i = 0; i < records.size(); ++i) {
            const Vec3 d = p - records[i].p;
            // The octree's reach is a little enlarged so rounding never drops a weight: test
            // strictly inside and strictly outside that margin.
            if (dot(d, d) <= records[i].support * records[i].support * 0.999f) want.push_back(static_cast<uint32_t>(i));
        }
        tree.visit(p, [&](uint32_t id) { got.push_back(id); });
        copy.visit(p, [&](uint32_t id) { got_copy.push_back(id); });
        std::sort(got.begin(), got.end());
        EXPECT_TRUE(std::adjacent_find(got.begin(), got.end()) == got.end()) << "a record visited twice";
        for (uint32_t id : got) {  // nothing far outside its support
            const Vec3 d = p - records[id].p;
            EXPECT_LE(dot(d, d), records[id].support * records[id].support * 1.01f);
        }
        EXPECT_TRUE(std::includes(got.begin(), got.end(), want.begin(), want.end())) << "a record whose support holds p was missed";
        std::sort(got_copy.begin(), got_copy.end());
        EXPECT_EQ(got, got_copy);
        hits += want.size();
    }
    EXPECT_GT(hits, 2000u);  // the queries did meet records
}

}  // namespace
}  // namespace bounce
