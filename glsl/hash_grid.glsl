// Hash grid over the iteration's light vertices (the grid-build pass, docs/design.md;
// SmallVCM's hashgrid.hxx, docs/smallvcm.md 4.3). Cells are cubes of side 2r (r = merge radius)
// anchored at `origin`; cell (x, y, z) maps to bucket
//   (uint(x) * 73856093 ^ uint(y) * 19349663 ^ uint(z) * 83492791) % num_buckets
// in wrapping 32-bit unsigned arithmetic. After the build (hash_grid_count.comp,
// exclusive_scan.comp, hash_grid_scatter.comp, hash_grid_sort.comp; driven by
// src/render/passes/hash_grid.rs) bucket b holds the entries grid_points[grid_start[b] ..
// grid_start[b + 1]), each (floatBitsToUint(position), slot), ascending by slot.
//
// This file declares no bindings: the including kernel owns the buffers (the bindings
// grid_start and grid_points; the camera kernel reads them through grid_start_at and
// grid_point_at).
//
// A query at q visits the buckets of the 2x2x2 cells nearest q: its own cell and, per axis,
// the neighbour on the side of the nearer face. With cells of side 2r every vertex within
// r of q lies in one of them (exactly, in exact arithmetic; with rounding only vertices at
// distance r to within float rounding may be missed). Distinct cells can share a bucket
// (hash collisions), so the caller must still test |p - q|^2 <= r^2 for every candidate.
#ifndef HASH_GRID_GLSL
#define HASH_GRID_GLSL

// Cell coordinates are clamped to +-2^30 before the float -> int conversion so that
// far-away (or non-finite) points give a defined cell; at that distance a float has no
// sub-cell precision left anyway.
const float HASH_GRID_MAX_CELL = 1073741824.0;

// Position in units of cells relative to `origin`. Build and query both go through
// here, so they agree bit for bit on which cell a point is in.
vec3 hash_grid_scaled(vec3 p, vec3 origin, float cell_size) {
    return (p - origin) * (1.0 / cell_size);
}

ivec3 hash_grid_cell_of_scaled(vec3 floor_x) {
    return ivec3(clamp(floor_x, vec3(-HASH_GRID_MAX_CELL), vec3(HASH_GRID_MAX_CELL)));
}

// The cell containing p: floor((p - origin) / cell_size) (cell_size = 2 r).
ivec3 hash_grid_cell(vec3 p, vec3 origin, float cell_size) {
    return hash_grid_cell_of_scaled(floor(hash_grid_scaled(p, origin, cell_size)));
}

// SmallVCM's spatial hash of a cell, in wrapping unsigned 32-bit arithmetic. For a
// power-of-two bucket count (what the renderer uses) the remainder is a mask: lavapipe
// computes a vector `%` as one integer division per lane, and a query hashes 8 cells.
// The branch is uniform (the count is a push constant), so only one side runs.
uint hash_grid_bucket(ivec3 cell, uint num_buckets) {
    uvec3 u = uvec3(cell);
    uint h = (u.x * 73856093u) ^ (u.y * 19349663u) ^ (u.z * 83492791u);
    if ((num_buckets & (num_buckets - 1u)) == 0u) return h & (num_buckets - 1u);
    return h % num_buckets;
}

// The bucket of the light vertex at p for merge radius `radius`.
uint hash_grid_point_bucket(vec3 p, vec3 origin, float radius, uint num_buckets) {
    return hash_grid_bucket(hash_grid_cell(p, origin, 2.0 * radius), num_buckets);
}

// The distinct buckets of the 2x2x2 cells nearest q (q's cell plus, per axis, the
// neighbour across the nearer face), in a fixed order; returns how many (1..8).
// buckets[i] for i >= the returned count is undefined.
uint hash_grid_query_cells(vec3 q, vec3 origin, float radius, uint num_buckets, out uint buckets[8]) {
    vec3 x = hash_grid_scaled(q, origin, 2.0 * radius);
    vec3 fl = floor(x);
    vec3 frac_x = x - fl;
    ivec3 base = hash_grid_cell_of_scaled(fl);
    ivec3 step = ivec3(frac_x.x < 0.5 ? -1 : 1, frac_x.y < 0.5 ? -1 : 1, frac_x.z < 0.5 ? -1 : 1);
    uint n = 0u;
    for (int i = 0; i < 8; ++i) {
        ivec3 cell = base + ivec3(i & 1, (i >> 1) & 1, (i >> 2) & 1) * step;
        uint b = hash_grid_bucket(cell, num_buckets);
        bool seen = false;
        for (uint j = 0u; j < n; ++j) {
            seen = seen || buckets[j] == b;
        }
        if (!seen) {
            buckets[n] = b;
            n += 1u;
        }
    }
    return n;
}

// ---- Build kernels only ----

// The build's buffers besides grid_start, by device address or as storage buffers: the
// light-vertex store's light_vertices_a (lv_a[], two vec4 per vertex, position in the
// first) and light_vertex_offsets (lv_offsets[], light path p's vertices are
// lv_offsets[p] .. lv_offsets[p + 1] - 1), grid_keys (vertex_keys[], uvec2 per vertex)
// and grid_points (bucket_points[], uvec4).
#if DEVICE_ADDRESSES
#define lv_a FRAME_LIGHT_VERTICES_A
#define lv_offsets FRAME_LIGHT_VERTEX_OFFSETS
#define vertex_keys FRAME_GRID_KEYS
#define bucket_points FRAME_GRID_POINTS
#define HASH_GRID_BUILD_BUFFERS
#else
#define HASH_GRID_BUILD_BUFFERS                                                           \
    layout(std430) readonly buffer light_vertices_a { vec4 lv_a[]; };                     \
    layout(std430) readonly buffer light_vertex_offsets { uint lv_offsets[]; };           \
    layout(std430) buffer grid_keys { uvec2 vertex_keys[]; };                             \
    layout(std430) buffer grid_points { uvec4 bucket_points[]; };
#endif

// Push constants of the build passes (mirrored by BuildPush in src/render/passes/hash_grid.rs).
#define HASH_GRID_BUILD_PUSH                                                              \
    layout(push_constant) uniform HashGridBuildPush {                                     \
        vec3 origin;                                                                      \
        float radius;                                                                     \
        uint light_paths;                                                                 \
        uint capacity;  /* vertices the store holds */                                    \
        uint num_buckets;                                                                 \
    } push

#endif
