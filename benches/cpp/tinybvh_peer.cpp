// tinybvh (the single header shipped in the tinybvh-rs crate) behind a small C ABI for the
// `peers` comparison: builds of BVH8_CPU and BVH4_CPU by `Build` or `BuildHQ` (spatial splits),
// with or without tinybvh's threaded builder, and the two queries, one ray at a time. Compiled
// by benches/build.rs with -O3 -march=native (tinybvh's BVH8_CPU needs AVX2 and FMA).
#define TINYBVH_IMPLEMENTATION
#include "tiny_bvh.h"

#include <cstdint>
#include <new>
#include <utility>
#include <vector>

using tinybvh::bvhvec3;
using tinybvh::bvhvec4;

namespace {

// The binary BVH inside each layout: its builder decides the threading.
tinybvh::BVH& inner_of(tinybvh::BVH8_CPU& b) { return b.bvh8.bvh; }
tinybvh::BVH& inner_of(tinybvh::BVH4_CPU& b) { return b.bvh4.bvh; }

template <typename B>
void* build_layout(const float* verts, uint32_t tris, bool threaded, bool hq) {
    B* b = new (std::nothrow) B();
    if (!b) return nullptr;
    // Cleared before the build: tinybvh clears it itself under 50k triangles, never sets it
    // (in either builder).
    inner_of(*b).threadedBuild = threaded;
    const bvhvec4* v = reinterpret_cast<const bvhvec4*>(verts);
    // BuildHQ differs from Build only in the binary builder (the SBVH one); the leaf regrouping
    // and the collapse into the layout are the same.
    if (hq) {
        b->BuildHQ(v, tris);
    } else {
        b->Build(v, tris);
    }
    return b;
}

// The most stack entries the layout's traversals (`Intersect`, `IsOccluded`: fixed arrays of
// 256) can need on `m`: along a path from the root, each inner node leaves all its children but
// the one it enters on the stack, and the traversal writes 8 entries at once where it pushes.
// Counted on every child, hit or not, so it bounds every ray. Iterative: a degenerate tree can be
// thousands of levels deep.
template <int M>
uint32_t stack_need(const tinybvh::MBVH<M>& m) {
    if (m.usedNodes == 0) return 0;
    std::vector<std::pair<uint32_t, uint32_t>> todo{{0, 0}};
    uint32_t most = 0;
    while (!todo.empty()) {
        const auto [node, below] = todo.back();
        todo.pop_back();
        const auto& n = m.mbvhNode[node];
        if (n.isLeaf()) continue;
        uint32_t kids = 0;
        for (int i = 0; i < M; i++) kids += n.child[i] != 0;
        if (below + 8 > most) most = below + 8;
        for (int i = 0; i < M; i++)
            if (n.child[i]) todo.push_back({n.child[i], below + kids - 1});
    }
    return most;
}

template <typename B>
float closest(const void* b, const tinybvh::Ray* ray) {
    tinybvh::Ray r = *ray;
    static_cast<const B*>(b)->Intersect(r);
    return r.hit.t;
}

template <typename B>
bool occluded(const void* b, const tinybvh::Ray* ray) {
    return static_cast<const B*>(b)->IsOccluded(*ray);
}

}  // namespace

extern "C" {

// The size and alignment of tinybvh::Ray, for the Rust side's opaque copy.
uint32_t rdbvh_tinybvh_ray_size() { return sizeof(tinybvh::Ray); }
uint32_t rdbvh_tinybvh_ray_align() { return alignof(tinybvh::Ray); }

// tinybvh's own ray constructor (it normalises the direction and sets 1/D) into `out`, which
// has room and alignment for a tinybvh::Ray. `t` is the segment end along the unit direction.
void rdbvh_tinybvh_ray(const float* o, const float* d, float t, void* out) {
    new (out) tinybvh::Ray(bvhvec3(o[0], o[1], o[2]), bvhvec3(d[0], d[1], d[2]), t);
}

// `verts`: 3 * tris vertices of 4 floats each (x, y, z, unused), 16-byte aligned; `hq`:
// BuildHQ instead of Build. Null when out of memory.
void* rdbvh_tinybvh8_build(const float* verts, uint32_t tris, bool threaded, bool hq) {
    return build_layout<tinybvh::BVH8_CPU>(verts, tris, threaded, hq);
}
void rdbvh_tinybvh8_free(void* b) { delete static_cast<tinybvh::BVH8_CPU*>(b); }
// The hit distance along the unit direction, or the ray's own `t` (its segment end) on a miss.
float rdbvh_tinybvh8_closest(const void* b, const void* ray) {
    return closest<tinybvh::BVH8_CPU>(b, static_cast<const tinybvh::Ray*>(ray));
}
bool rdbvh_tinybvh8_occluded(const void* b, const void* ray) {
    return occluded<tinybvh::BVH8_CPU>(b, static_cast<const tinybvh::Ray*>(ray));
}
// The traversal stack entries the tree can need (see `stack_need`); tinybvh's hold 256.
uint32_t rdbvh_tinybvh8_stack_need(const void* b) {
    return stack_need(static_cast<const tinybvh::BVH8_CPU*>(b)->bvh8);
}

void* rdbvh_tinybvh4_build(const float* verts, uint32_t tris, bool threaded, bool hq) {
    return build_layout<tinybvh::BVH4_CPU>(verts, tris, threaded, hq);
}
void rdbvh_tinybvh4_free(void* b) { delete static_cast<tinybvh::BVH4_CPU*>(b); }
float rdbvh_tinybvh4_closest(const void* b, const void* ray) {
    return closest<tinybvh::BVH4_CPU>(b, static_cast<const tinybvh::Ray*>(ray));
}
bool rdbvh_tinybvh4_occluded(const void* b, const void* ray) {
    return occluded<tinybvh::BVH4_CPU>(b, static_cast<const tinybvh::Ray*>(ray));
}
uint32_t rdbvh_tinybvh4_stack_need(const void* b) {
    return stack_need(static_cast<const tinybvh::BVH4_CPU*>(b)->bvh4);
}

}  // extern "C"
