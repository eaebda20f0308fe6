#include "bounce/accel/parts.h"

#include <OpenImageIO/hash.h>

#include <unordered_map>

#include "bounce/core/random.h"

namespace bounce {

namespace {
/// What a part is built from, hashed (xxHash): equal keys, equal parts. Every key holds the
/// number of objects: fur's geometry ids (and so its hits) depend on it.
class PartKey {
  public:
    PartKey(uint64_t kind, size_t objects) : h_(hash_combine(mix64(kind + 1), objects)) {}
    PartKey& add(uint64_t v) {
        h_ = hash_combine(h_, v);
        return *this;
    }
    template <class T>
    PartKey& add(const std::vector<T>& v) {
        add(v.size());
        h_ = OIIO::xxhash::XXH64(v.data(), v.size() * sizeof(T), h_);
        return *this;
    }
    uint64_t value() const { return h_; }

  private:
    uint64_t h_;
};

enum : uint64_t { kStill, kLocal, kWorld, kFur, kLayout, kPrototype };

bool moving_in_shutter(const Object& o) {
    return !o.shutter[0].empty() || (o.shutter_placement && !((*o.shutter_placement)[0] == (*o.shutter_placement)[1]));
}

uint64_t fur_key(const BvhGeometry& g) {
    PartKey k(kFur, g.meshes.size());
    for (size_t i = 0; i < g.furs.size(); ++i) {
        if (!g.furs[i]) continue;
        k.add(i).add(g.furs[i]->vertices).add(g.furs[i]->segment_first).add(i < g.fur_masks.size() ? g.fur_masks[i] : kRayAll);
        if (i < g.fur_motion.size() && g.fur_motion[i]) k.add((*g.fur_motion[i])[0]).add((*g.fur_motion[i])[1]);
    }
    return k.value();
}
}  // namespace

FurLists::FurLists(const Scene& scene) {
    for (size_t i = 0; i < scene.objects.size(); ++i) {
        const Object& o = scene.objects[i];
        const Fur* f = o.fur && o.fur->segment_count() ? o.fur.get() : nullptr;
        const RayVisibility to = f ? f->params.visible_to : RayVisibility{};
        masks.push_back(fur_ray_mask(scene, i));
        visible.push_back(f && to.camera ? f : nullptr);
        indirect.push_back(f && (to.indirect || to.reflections) ? f : nullptr);
        shadow.push_back(f && to.shadows && !indirect.back() ? f : nullptr);
        motion.push_back(f && !o.fur_shutter[0].empty() ? &o.fur_shutter : nullptr);
    }
}

bool FurLists::any(const std::vector<const Fur*>& furs) {
    return std::any_of(furs.begin(), furs.end(), [](const Fur* f) { return f != nullptr; });
}

BvhPart BvhParts::take(const BvhPart* before, uint64_t key, uint64_t layout, const std::function<std::shared_ptr<Bvh>()>& build,
                       const std::function<void(Bvh&)>& refit) {
    // A part a later frame refit traces other positions than its key says: never taken.
    if (before && before->bvh && before->bvh->refits() == before->refits) {
        if (before->key == key) {
            ++reuse_.kept;
            return *before;
        }
        if (layout != 0 && before->layout == layout) {
            refit(*before->bvh);
            before->bvh->commit();
            ++reuse_.refit;
            return {before->bvh, key, layout, before->bvh->refits(), before->furs};
        }
    }
    ++reuse_.built;
    std::shared_ptr<Bvh> bvh = build();
    return {bvh, key, layout, bvh ? bvh->refits() : 0, {}};
}

BvhParts::BvhParts(RTCDevice device, const Scene& scene, const BvhParts* before) {
    take_still(device, scene, before);
    take_movers(device, scene, before);
    take_fur(device, scene, before);
    take_prototypes(device, scene, before);
}

void BvhParts::take_still(RTCDevice device, const Scene& scene, const BvhParts* before) {
    const size_t n = scene.objects.size();
    BvhGeometry coarse;
    coarse.meshes.assign(n, nullptr), coarse.masks.assign(n, kRayAll);
    BvhGeometry fine = coarse;
    PartKey coarse_key(kStill, n), fine_key(kStill, n);
    bool any = false;
    for (size_t i = 0; i < n; ++i) {
        const Object& o = scene.objects[i];
        if (o.moves || o.instance || !o.placed()) continue;
        any = true;
        const unsigned mask = coarse.masks[i] = fine.masks[i] = object_ray_mask(scene, i);
        coarse.meshes[i] = &o.coarse, fine.meshes[i] = &o.visible();
        coarse_key.add(i).add(o.coarse.positions).add(o.coarse.indices).add(mask).add(CutoutMesh::key(scene.materials, o.coarse));
        fine_key.add(i).add(o.visible().positions).add(o.visible().indices).add(mask).add(CutoutMesh::key(scene.materials, o.visible()));
        needs_fine_ = needs_fine_ || o.has_fine();
    }
    if (!any) return;
    auto build = [&](BvhGeometry& g) {
        return [&] {
            g.cutouts.assign(n, nullptr);
            for (size_t i = 0; i < n; ++i)
                if (g.meshes[i]) g.cutouts[i] = CutoutMesh::make(scene.materials, *g.meshes[i]);
            return std::make_shared<Bvh>(device, g);
        };
    };
    auto none = [](Bvh&) {};
    still_coarse_ = take(before ? &before->still_coarse_ : nullptr, coarse_key.value(), 0, build(coarse), none);
    // Without finer tessellations the camera's part is the same part.
    still_fine_ = fine_key.value() == coarse_key.value()
                      ? still_coarse_
                      : take(before ? &before->still_fine_ : nullptr, fine_key.value(), 0, build(fine), none);
}

void BvhParts::take_movers(RTCDevice device, const Scene& scene, const BvhParts* before) {
    const size_t n = scene.objects.size();
    coarse_.resize(n), fine_.resize(n);
    for (size_t i = 0; i < n; ++i) {
        const Object& o = scene.objects[i];
        if (!o.moves) continue;
        const BvhPart* was_coarse = before && i < before->coarse_.size() ? &before->coarse_[i] : nullptr;
        const BvhPart* was_fine = before && i < before->fine_.size() ? &before->fine_[i] : nullptr;
        needs_fine_ = needs_fine_ || o.has_fine() || moving_in_shutter(o);
        // Each mover's part holds its mesh alone, under its own id (so hits decode as the flat BVH's).
        auto build = [&](const TriangleMesh& mesh, const ShutterPositions* motion, bool refittable) {
            return [&, motion, refittable] {
                BvhGeometry g;
                g.meshes.assign(n, nullptr), g.motion.assign(n, nullptr);
                g.meshes[i] = &mesh, g.motion[i] = motion, g.refittable = refittable;
                g.cutouts.assign(n, nullptr);
                g.cutouts[i] = CutoutMesh::make(scene.materials, mesh);
                return std::make_shared<Bvh>(device, g);
            };
        };
        if (o.local_coarse) {  // rigid: its shape before the placement, placed at every frame
            const TriangleMesh &lc = *o.local_coarse, &lf = o.local_fine ? *o.local_fine : lc;
            const uint64_t kc =
                PartKey(kLocal, n).add(i).add(lc.positions).add(lc.indices).add(CutoutMesh::key(scene.materials, lc)).value();
            const uint64_t kf =
                PartKey(kLocal, n).add(i).add(lf.positions).add(lf.indices).add(CutoutMesh::key(scene.materials, lf)).value();
            auto none = [](Bvh&) {};
            coarse_[i] = take(was_coarse, kc, 0, build(lc, nullptr, false), none);
            fine_[i] = kf == kc ? coarse_[i] : take(was_fine, kf, 0, build(lf, nullptr, false), none);
            continue;
        }
        // Deforming (or a subdivision surface placed anew): where it is this frame; refit when
        // its triangles are the ones of the frame before.
        const TriangleMesh &c = o.coarse, &v = o.visible();
        const ShutterPositions* motion = o.shutter[0].empty() ? nullptr : &o.shutter;
        PartKey kc(kWorld, n), kf(kWorld, n);
        kc.add(i), kf.add(i);
        kc.add(c.positions).add(c.indices).add(CutoutMesh::key(scene.materials, c));
        kf.add(v.positions).add(v.indices).add(CutoutMesh::key(scene.materials, v));
        if (motion) kf.add((*motion)[0]).add((*motion)[1]);
        // A refit keeps the part's cutouts: their uvs and materials must be the same.
        auto layout = [&](const TriangleMesh& m, bool moving) {
            return o.deforms ? PartKey(kLayout, n)
                                   .add(i)
                                   .add(m.indices)
                                   .add(m.positions.size())
                                   .add(moving ? 2 : 1)
                                   .add(CutoutMesh::key(scene.materials, m))
                                   .value()
                             : 0;
        };
        coarse_[i] = take(was_coarse, kc.value(), layout(c, false), build(c, nullptr, o.deforms),
                          [&](Bvh& b) { b.refit(static_cast<unsigned>(i), c, nullptr); });
        fine_[i] = kf.value() == kc.value() ? coarse_[i]
                                            : take(was_fine, kf.value(), layout(v, motion != nullptr), build(v, motion, o.deforms),
                                                   [&](Bvh& b) { b.refit(static_cast<unsigned>(i), v, motion); });
    }
}

void BvhParts::take_fur(RTCDevice device, const Scene& scene, const BvhParts* before) {
    const FurLists lists(scene);
    const size_t n = scene.objects.size();
    // Fur alone, over as many mesh ids as objects (so its hits decode as every part's).
    auto take_list = [&](BvhPart BvhParts::*slot, const std::vector<const Fur*>& furs, const std::vector<unsigned>& masks,
                         const std::vector<const FurShutter*>& motion) {
        if (!FurLists::any(furs)) return;
        BvhGeometry g;
        g.meshes.assign(n, nullptr), g.furs = furs, g.fur_masks = masks, g.fur_motion = motion;
        BvhPart& part = this->*slot;
        part = take(
            before ? &(before->*slot) : nullptr, fur_key(g), 0, [&] { return std::make_shared<Bvh>(device, g); }, [](Bvh&) {});
        if (part.furs.empty())  // built now: it traces this scene's fur buffers, which must outlive it
            for (size_t i = 0; i < n; ++i)
                if (g.furs[i]) part.furs.push_back(scene.objects[i].fur);
    };
    take_list(&BvhParts::coarse_fur_, lists.indirect, lists.masks, {});
    take_list(&BvhParts::shadow_fur_, lists.shadow, {}, {});
    // The camera sees all fur, still: when that is the shadow part's, the same part.
    const bool blurred = std::any_of(lists.motion.begin(), lists.motion.end(), [](const FurShutter* m) { return m != nullptr; });
    if (lists.visible == lists.shadow && !blurred)
        fine_fur_ = shadow_fur_;
    else
        take_list(&BvhParts::fine_fur_, lists.visible, {}, lists.motion);
    needs_fine_ = needs_fine_ || fine_fur_.bvh != nullptr;
}

void BvhParts::take_prototypes(RTCDevice device, const Scene& scene, const BvhParts* before) {
    std::unordered_map<const TriangleMesh*, size_t> seen;  // instances share their prototype's meshes
    const auto was = [&](uint64_t key, BvhPart Prototype::*part) -> const BvhPart* {
        if (before)
            for (const Prototype& p : before->prototypes_)
                if ((p.*part).key == key) return &(p.*part);
        return nullptr;
    };
    for (size_t i = 0; i < scene.objects.size(); ++i) {
        const Object& o = scene.objects[i];
        if (!o.instance) continue;
        const auto [it, fresh] = seen.emplace(o.local_coarse.get(), prototypes_.size());
        if (!fresh) {
            prototypes_[it->second].instances.push_back(static_cast<uint32_t>(i));
            continue;
        }
        const TriangleMesh &c = *o.local_coarse, &f = o.local_fine ? *o.local_fine : c;
        const uint64_t kc = PartKey(kPrototype, 1).add(c.positions).add(c.indices).add(CutoutMesh::key(scene.materials, c)).value();
        const uint64_t kf = PartKey(kPrototype, 1).add(f.positions).add(f.indices).add(CutoutMesh::key(scene.materials, f)).value();
        const auto build = [&](const TriangleMesh& mesh) {
            return [&] {
                BvhGeometry g;
                g.meshes = {&mesh};
                g.cutouts = {CutoutMesh::make(scene.materials, mesh)};
                return std::make_shared<Bvh>(device, g);
            };
        };
        const auto none = [](Bvh&) {};
        Prototype p;
        p.coarse = take(was(kc, &Prototype::coarse), kc, 0, build(c), none);
        p.fine = kf == kc ? p.coarse : take(was(kf, &Prototype::fine), kf, 0, build(f), none);
        p.instances.push_back(static_cast<uint32_t>(i));
        prototypes_.push_back(std::move(p));
        needs_fine_ = needs_fine_ || o.local_fine;
    }
}

void BvhParts::place_instances(const Scene& scene, bool fine, std::vector<Bvh::Placed>& placed) const {
    for (const Prototype& p : prototypes_)
        for (uint32_t i : p.instances) {
            const Transform& at = scene.objects[i].placement;
            placed.push_back({(fine ? p.fine : p.coarse).bvh, {at, at}, false, object_ray_mask(scene, i), i});
        }
}

namespace {
const std::array<Transform, 2> kIdentity{};

/// Where object `o`'s part is placed: a rigid mover's placement (at shutter open and close for
/// the camera's BVH when it moves in the shutter), else where it is.
Bvh::Placed placed_mover(const Object& o, const std::shared_ptr<Bvh>& bvh, unsigned mask, bool camera) {
    Bvh::Placed p{bvh, kIdentity, false, mask};
    if (!o.local_coarse) return p;
    p.at = {o.placement, o.placement};
    if (camera && o.shutter_placement) p.at = *o.shutter_placement, p.moving = !(p.at[0] == p.at[1]);
    return p;
}
}  // namespace

std::unique_ptr<Bvh> BvhParts::coarse(RTCDevice device, const Scene& scene) const {
    std::vector<Bvh::Placed> placed{{still_coarse_.bvh, kIdentity, false, kRayAll}};
    for (size_t i = 0; i < coarse_.size(); ++i)
        if (coarse_[i].bvh) placed.push_back(placed_mover(scene.objects[i], coarse_[i].bvh, object_ray_mask(scene, i), false));
    placed.push_back({coarse_fur_.bvh, kIdentity, false, kRayAll});
    place_instances(scene, false, placed);
    return std::make_unique<Bvh>(device, placed, static_cast<unsigned>(scene.objects.size()));
}

std::unique_ptr<Bvh> BvhParts::fine(RTCDevice device, const Scene& scene) const {
    if (!needs_fine_) return nullptr;
    std::vector<Bvh::Placed> placed{{still_fine_.bvh, kIdentity, false, kRayAll}};
    for (size_t i = 0; i < fine_.size(); ++i)
        if (fine_[i].bvh) placed.push_back(placed_mover(scene.objects[i], fine_[i].bvh, object_ray_mask(scene, i), true));
    placed.push_back({fine_fur_.bvh, kIdentity, false, kRayAll});
    place_instances(scene, true, placed);
    return std::make_unique<Bvh>(device, placed, static_cast<unsigned>(scene.objects.size()));
}

const Bvh* BvhParts::coarse_part(size_t id) const { return id < coarse_.size() ? coarse_[id].bvh.get() : nullptr; }

bool BvhParts::current() const {
    auto ok = [](const BvhPart& p) { return !p.bvh || p.bvh->refits() == p.refits; };
    return ok(still_coarse_) && ok(still_fine_) && ok(coarse_fur_) && ok(fine_fur_) && ok(shadow_fur_) &&
           std::all_of(prototypes_.begin(), prototypes_.end(), [&](const Prototype& p) { return ok(p.coarse) && ok(p.fine); }) &&
           std::all_of(coarse_.begin(), coarse_.end(), ok) && std::all_of(fine_.begin(), fine_.end(), ok);
}

}  // namespace bounce
