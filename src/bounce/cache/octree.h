// Spatial index over cache records with their reach (pbrt-v2/Mitsuba style): a record is
// stored in every node its support box overlaps, down to nodes about its size, so a lookup
// only walks the single root-to-leaf path containing the query point. Built and grown between
// sub-passes; any number of threads may read it while nobody inserts.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "bounce/core/math.h"

namespace bounce {

class RecordOctree {
  public:
    explicit RecordOctree(const Bounds& bounds);
    RecordOctree(const RecordOctree& other);  ///< a deep copy
    RecordOctree& operator=(const RecordOctree&) = delete;
    RecordOctree(RecordOctree&&) = default;
    RecordOctree& operator=(RecordOctree&&) = default;
    /// Adds record `id` whose weights vanish beyond `support` from `p`.
    void insert(uint32_t id, const Vec3& p, float support);
    /// Calls f(id) for every record whose support sphere contains p (a superset of the records
    /// with nonzero weight at p).
    template <typename F>
    void visit(const Vec3& p, F&& f) const {
        visit_until(p, [&f](uint32_t id) {
            f(id);
            return false;
        });
    }
    /// The same walk, ended as soon as f(id) returns true (a lookup that has its answer).
    template <typename F>
    void visit_until(const Vec3& p, F&& f) const {
        const Node* node = &root_;
        Vec3 lo = bounds_.lo, hi = bounds_.hi;
        while (node) {
            for (const Entry& e : node->entries) {
                const Vec3 d = p - e.p;
                if (dot(d, d) <= e.reach2 && f(e.id)) return;
            }
            Vec3 mid = (lo + hi) * 0.5f;
            int c = (p.x > mid.x ? 1 : 0) | (p.y > mid.y ? 2 : 0) | (p.z > mid.z ? 4 : 0);
            if (!node->children) break;
            lo = {c & 1 ? mid.x : lo.x, c & 2 ? mid.y : lo.y, c & 4 ? mid.z : lo.z};
            hi = {c & 1 ? hi.x : mid.x, c & 2 ? hi.y : mid.y, c & 4 ? hi.z : mid.z};
            node = &(*node->children)[static_cast<size_t>(c)];
        }
    }
    size_t memory_bytes() const;

  private:
    /// A record as the walk needs it: most records on a path lie outside their support sphere
    /// (nodes hold support boxes), and are skipped without touching the record itself.
    struct Entry {
        Vec3 p;
        float reach2;  ///< squared support, a little enlarged so rounding never drops a weight
        uint32_t id;
    };
    struct Node {
        std::vector<Entry> entries;
        std::unique_ptr<std::array<Node, 8>> children;
    };
    static Node copy(const Node& node);
    void insert(Node& node, const Vec3& lo, const Vec3& hi, const Entry& e, const Vec3& blo, const Vec3& bhi, float diag2, int depth);
    Bounds bounds_;
    Node root_;
    size_t nodes_ = 1, refs_ = 0;
};

}  // namespace bounce
