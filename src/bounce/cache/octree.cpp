#include "bounce/cache/octree.h"

namespace bounce {

RecordOctree::RecordOctree(const Bounds& b) {
    // A cube slightly larger than the scene, so points on its faces are inside.
    Vec3 c = (b.lo + b.hi) * 0.5f, d = b.diagonal();
    float half = 0.5f * std::max({d.x, d.y, d.z}) * 1.01f + 1e-6f;
    bounds_.lo = c - Vec3(half);
    bounds_.hi = c + Vec3(half);
}

RecordOctree::RecordOctree(const RecordOctree& o) : bounds_(o.bounds_), root_(copy(o.root_)), nodes_(o.nodes_), refs_(o.refs_) {}

RecordOctree::Node RecordOctree::copy(const Node& node) {
    Node out;
    out.entries = node.entries;
    if (node.children) {
        out.children = std::make_unique<std::array<Node, 8>>();
        for (size_t c = 0; c < 8; ++c) (*out.children)[c] = copy((*node.children)[c]);
    }
    return out;
}

void RecordOctree::insert(uint32_t id, const Vec3& p, float support) {
    Vec3 blo = p - Vec3(support), bhi = p + Vec3(support);
    float diag2 = 12 * support * support;  // squared diagonal of the support box
    insert(root_, bounds_.lo, bounds_.hi, Entry{p, 1.0001f * support * support, id}, blo, bhi, diag2, 0);
}

void RecordOctree::insert(Node& node, const Vec3& lo, const Vec3& hi, const Entry& e, const Vec3& blo, const Vec3& bhi, float diag2,
                          int depth) {
    Vec3 d = hi - lo;
    // Stop at nodes no bigger than the support box (or at depth 16).
    if (depth == 16 || dot(d, d) < diag2) {
        node.entries.push_back(e);
        ++refs_;
        return;
    }
    if (!node.children) {
        node.children = std::make_unique<std::array<Node, 8>>();
        nodes_ += 8;
    }
    Vec3 mid = (lo + hi) * 0.5f;
    // Per axis, whether the box reaches the lower and the upper half (closed intervals, as
    // the children's own bounds): the children it overlaps are their products.
    bool low[3], high[3];
    for (int a = 0; a < 3; ++a) {
        low[a] = bhi[a] >= lo[a] && blo[a] <= mid[a];
        high[a] = bhi[a] >= mid[a] && blo[a] <= hi[a];
    }
    for (int c = 0; c < 8; ++c) {
        if (!(c & 1 ? high[0] : low[0]) || !(c & 2 ? high[1] : low[1]) || !(c & 4 ? high[2] : low[2])) continue;
        Vec3 clo{c & 1 ? mid.x : lo.x, c & 2 ? mid.y : lo.y, c & 4 ? mid.z : lo.z};
        Vec3 chi{c & 1 ? hi.x : mid.x, c & 2 ? hi.y : mid.y, c & 4 ? hi.z : mid.z};
        insert((*node.children)[static_cast<size_t>(c)], clo, chi, e, blo, bhi, diag2, depth + 1);
    }
}

size_t RecordOctree::memory_bytes() const { return nodes_ * sizeof(Node) + refs_ * sizeof(Entry); }

}  // namespace bounce
