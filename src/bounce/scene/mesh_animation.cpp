#include "bounce/scene/mesh_animation.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "bounce/core/error.h"

namespace bounce {

namespace {

/// The key interval of `t` in keys[0..n): index of the key before it and the fraction to the next.
template <typename Key>
std::pair<unsigned, double> bracket(const Key* keys, unsigned n, double t) {
    if (n == 0 || t <= keys[0].mTime) return {0, 0.0};
    if (t >= keys[n - 1].mTime) return {n - 1, 0.0};
    unsigned i = 0;
    while (i + 1 < n && keys[i + 1].mTime <= t) ++i;
    const double span = keys[i + 1].mTime - keys[i].mTime;
    return {i, span > 0 ? (t - keys[i].mTime) / span : 0.0};
}

aiVector3D lerp(const aiVectorKey* keys, unsigned n, double t, const aiVector3D& rest) {
    if (n == 0) return rest;
    const auto [i, f] = bracket(keys, n, t);
    if (f == 0) return keys[i].mValue;
    return keys[i].mValue + (keys[i + 1].mValue - keys[i].mValue) * static_cast<ai_real>(f);
}

aiQuaternion slerp(const aiQuatKey* keys, unsigned n, double t, const aiQuaternion& rest) {
    if (n == 0) return rest;
    const auto [i, f] = bracket(keys, n, t);
    if (f == 0) return keys[i].mValue;
    aiQuaternion out;
    aiQuaternion::Interpolate(out, keys[i].mValue, keys[i + 1].mValue, static_cast<ai_real>(f));
    return out.Normalize();
}

/// Ticks of the clip at `seconds` (Assimp's time unit; glTF's importer counts milliseconds).
double ticks(const aiAnimation* a, double seconds) {
    const double per_second = a->mTicksPerSecond > 0 ? a->mTicksPerSecond : 25.0;
    return std::clamp(seconds * per_second, 0.0, a->mDuration);
}

Vec3 to_vec3(const aiVector3D& v) { return {v.x, v.y, v.z}; }

/// Whether the node named `node` (a morph channel's target: glTF animates a node's weights)
/// draws `mesh`. The binding is glTF's node -> mesh reference, not a match of names: a mesh may
/// be unnamed or named unlike its node.
bool node_shows(const aiScene* s, const aiString& node, const aiMesh* mesh) {
    const aiNode* n = s->mRootNode->FindNode(node);
    if (!n) return false;
    for (unsigned i = 0; i < n->mNumMeshes; ++i)
        if (n->mMeshes[i] < s->mNumMeshes && s->mMeshes[n->mMeshes[i]] == mesh) return true;
    return false;
}

/// Key times that are finite and increasing (glTF's sampler input; Assimp keeps NaN and
/// decreasing times, which bracket() would search wrongly).
template <typename Key>
void check_times(const Key* keys, unsigned n, const std::string& path, const std::string& where) {
    for (unsigned i = 0; i < n; ++i)
        if (!std::isfinite(keys[i].mTime) || (i > 0 && !(keys[i].mTime > keys[i - 1].mTime)))
            throw InputError(path, where, fmt::format("key {} time {} is not finite and after the key before", i, keys[i].mTime));
}

void check_clip(const aiAnimation* a, int clip, const std::string& path) {
    for (unsigned c = 0; c < a->mNumChannels; ++c) {
        const aiNodeAnim* ch = a->mChannels[c];
        const std::string where = fmt::format("animation {} channel {} (node \"{}\")", clip, c, ch->mNodeName.C_Str());
        check_times(ch->mPositionKeys, ch->mNumPositionKeys, path, where);
        check_times(ch->mRotationKeys, ch->mNumRotationKeys, path, where);
        check_times(ch->mScalingKeys, ch->mNumScalingKeys, path, where);
    }
    for (unsigned c = 0; c < a->mNumMorphMeshChannels; ++c)
        check_times(a->mMorphMeshChannels[c]->mKeys, a->mMorphMeshChannels[c]->mNumKeys, path,
                    fmt::format("animation {} morph channel {}", clip, c));
}

}  // namespace

int find_clip(const aiScene* s, const std::string& name, const std::string& path) {
    std::vector<std::string> names;
    for (unsigned i = 0; i < s->mNumAnimations; ++i) {
        names.push_back(s->mAnimations[i]->mName.C_Str());
        if (names.back() == name || std::to_string(i) == name) {
            check_clip(s->mAnimations[i], static_cast<int>(i), path);
            return static_cast<int>(i);
        }
    }
    throw NoSuchClip(path, "animations",
                     fmt::format("no animation \"{}\" (the file has {})", name,
                                 names.empty() ? std::string("none") : fmt::format("{}", fmt::join(names, ", "))));
}

std::unordered_map<const aiNode*, aiMatrix4x4> posed_nodes(const aiScene* s, const MeshTime& t, const std::string& path) {
    std::unordered_map<const aiNode*, aiMatrix4x4> local;
    if (t.clip >= 0 && static_cast<unsigned>(t.clip) < s->mNumAnimations) {
        const aiAnimation* a = s->mAnimations[t.clip];
        const double at = ticks(a, t.seconds);
        for (unsigned c = 0; c < a->mNumChannels; ++c) {
            const aiNodeAnim* ch = a->mChannels[c];
            const aiNode* node = s->mRootNode->FindNode(ch->mNodeName);
            if (!node)
                throw InputError(path, fmt::format("animation {} channel {}", t.clip, c),
                                 fmt::format("animates node \"{}\", which the file does not have", ch->mNodeName.C_Str()));
            aiVector3D scale, position;
            aiQuaternion rotation;
            node->mTransformation.Decompose(scale, rotation, position);
            const aiVector3D p = lerp(ch->mPositionKeys, ch->mNumPositionKeys, at, position);
            const aiVector3D sc = lerp(ch->mScalingKeys, ch->mNumScalingKeys, at, scale);
            const aiQuaternion q = slerp(ch->mRotationKeys, ch->mNumRotationKeys, at, rotation);
            local[node] = aiMatrix4x4(sc, q, p);
        }
    }
    // World transforms, parents first, without recursion (the node depth is bounded anyway).
    std::unordered_map<const aiNode*, aiMatrix4x4> world;
    std::vector<const aiNode*> stack{s->mRootNode};
    while (!stack.empty()) {
        const aiNode* n = stack.back();
        stack.pop_back();
        const auto it = local.find(n);
        const aiMatrix4x4& own = it != local.end() ? it->second : n->mTransformation;
        world[n] = n->mParent ? world[n->mParent] * own : own;
        for (unsigned c = 0; c < n->mNumChildren; ++c) stack.push_back(n->mChildren[c]);
    }
    return world;
}

void pose_mesh(const aiScene* s, const aiMesh* mesh, const MeshTime& t, const aiMatrix4x4& node_world,
               const std::unordered_map<const aiNode*, aiMatrix4x4>& nodes, std::vector<Vec3>& positions, std::vector<Vec3>& normals,
               const std::string& path) {
    const unsigned nv = mesh->mNumVertices;
    // Morph targets first (in the mesh's own space): base + sum of weights x (target - base).
    std::vector<aiVector3D> base(mesh->mVertices, mesh->mVertices + nv);
    if (mesh->mNumAnimMeshes > 0) {
        std::vector<double> weights(mesh->mNumAnimMeshes);
        for (unsigned k = 0; k < mesh->mNumAnimMeshes; ++k) weights[k] = mesh->mAnimMeshes[k]->mWeight;
        if (t.clip >= 0 && static_cast<unsigned>(t.clip) < s->mNumAnimations) {
            const aiAnimation* a = s->mAnimations[t.clip];
            for (unsigned c = 0; c < a->mNumMorphMeshChannels; ++c) {
                const aiMeshMorphAnim* m = a->mMorphMeshChannels[c];
                if (m->mNumKeys == 0 || !node_shows(s, m->mName, mesh)) continue;
                const auto [i, f] = bracket(m->mKeys, m->mNumKeys, ticks(a, t.seconds));
                for (unsigned v = 0; v < m->mKeys[i].mNumValuesAndWeights; ++v) {
                    const unsigned target = m->mKeys[i].mValues[v];
                    double w = m->mKeys[i].mWeights[v];
                    if (f > 0 && v < m->mKeys[i + 1].mNumValuesAndWeights) w += f * (m->mKeys[i + 1].mWeights[v] - w);
                    if (target < weights.size()) weights[target] = w;
                }
            }
        }
        for (unsigned k = 0; k < mesh->mNumAnimMeshes; ++k) {
            const aiAnimMesh* am = mesh->mAnimMeshes[k];
            if (!std::isfinite(weights[k]))
                throw InputError(path, fmt::format("mesh {} morph target {}", mesh->mName.C_Str(), k), "weight is not finite");
            if (weights[k] == 0 || !am->mVertices || am->mNumVertices != nv) continue;
            for (unsigned v = 0; v < nv; ++v) base[v] += (am->mVertices[v] - mesh->mVertices[v]) * static_cast<ai_real>(weights[k]);
        }
    }
    positions.assign(nv, Vec3(0));
    normals.assign(mesh->mNormals ? nv : 0, Vec3(0));
    if (mesh->mNumBones == 0) {
        const aiMatrix3x3 rot(node_world);
        for (unsigned v = 0; v < nv; ++v) {
            positions[v] = to_vec3(node_world * base[v]);
            if (mesh->mNormals) normals[v] = to_vec3((rot * mesh->mNormals[v]).Normalize());
        }
        return;
    }
    // Skinning: each joint's world transform times its inverse bind matrix, weighted; the mesh
    // node's own transform does not apply (glTF 2.0, skins).
    std::vector<float> total(nv, 0.0f);
    for (unsigned b = 0; b < mesh->mNumBones; ++b) {
        const aiBone* bone = mesh->mBones[b];
        const aiNode* joint = s->mRootNode->FindNode(bone->mName);
        const std::string where = fmt::format("mesh {} joint {}", mesh->mName.C_Str(), b);
        if (!joint) throw InputError(path, where, fmt::format("names node \"{}\", which the file does not have", bone->mName.C_Str()));
        const aiMatrix4x4 m = nodes.at(joint) * bone->mOffsetMatrix;
        const aiMatrix3x3 rot(m);
        for (unsigned k = 0; k < bone->mNumWeights; ++k) {
            const aiVertexWeight& w = bone->mWeights[k];
            if (w.mVertexId >= nv) throw InputError(path, where, fmt::format("weights vertex {} of {}", w.mVertexId, nv));
            if (!(w.mWeight >= 0 && w.mWeight <= 1e6f))
                throw InputError(path, where, fmt::format("weight {} of vertex {} is negative or not finite", w.mWeight, w.mVertexId));
            positions[w.mVertexId] += to_vec3(m * base[w.mVertexId]) * w.mWeight;
            if (mesh->mNormals) normals[w.mVertexId] += to_vec3(rot * mesh->mNormals[w.mVertexId]) * w.mWeight;
            total[w.mVertexId] += w.mWeight;
        }
    }
    for (unsigned v = 0; v < nv; ++v) {
        // Weights that do not sum to 1 are normalised. A vertex of a skin that no joint moves is
        // a broken file (a joint index outside the skin, or all its weights zero).
        if (!(total[v] > 0))
            throw InputError(path, fmt::format("mesh {} vertex {}", mesh->mName.C_Str(), v),
                             "no joint of the skin moves it (a joint index outside the skin, or weights that are all zero)");
        positions[v] = positions[v] / total[v];
        if (mesh->mNormals) normals[v] = dot(normals[v], normals[v]) > 0 ? normalize(normals[v]) : to_vec3(mesh->mNormals[v]);
    }
}

}  // namespace bounce
