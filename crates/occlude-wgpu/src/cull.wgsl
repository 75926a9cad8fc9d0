// GPU-resident culling (culling.rs): compute passes over id lists and flag
// buffers, and the fragment stage of the batched box tests, whose vertex
// stage is vs_query_box of shader.wgsl.
//
// Each compute entry point runs one thread per list entry or flag slot, in
// workgroups of 64 laid out in two dimensions (a dimension holds at most
// 65535 workgroups); threads past the end return at once. Lists hold their
// length on the device, so the CPU never learns how many threads have work.

// A padded box; `id` is its slot in the box set.
struct Box {
    lo: vec3<f32>,
    id: u32,
    hi: vec3<f32>,
}

// An id list as read, and as written (appending bumps the count atomically).
// Writers drop ids past the capacity; readers stop at it.
struct ReadList {
    count: u32,
    capacity: u32,
    ids: array<u32>,
}

struct WriteList {
    count: atomic<u32>,
    capacity: u32,
    ids: array<u32>,
}

// The camera of the frame: the six frustum planes (inside: n.p + d >= 0) and
// the eye, its w the squared near-region radius (Camera::box_touches_near_region).
struct Cull {
    planes: array<vec4<f32>, 6>,
    eye: vec4<f32>,
}

// DrawIndexedIndirectArgs of the box-test draw; the CPU sets 36 corner indices
// and zeroes the instance count before each test.
struct BoxDraw {
    index_count: u32,
    instance_count: atomic<u32>,
    first_index: u32,
    base_vertex: i32,
    first_instance: u32,
}

// Where an instance's mesh lies in the pools, and its triangle count.
struct InstanceDraw {
    index_count: u32,
    first_index: u32,
    base_vertex: i32,
    triangles: u32,
}

// DrawIndexedIndirectArgs, tightly packed (20 bytes) as multi-draws read them.
struct DrawArgs {
    index_count: u32,
    instance_count: u32,
    first_index: u32,
    base_vertex: i32,
    first_instance: u32,
}

// Culling statistics of the frame, read back after it: list draws' draws,
// their triangles as a 64-bit count in two words, boxes the box tests
// rasterized, one bit per instance drawn.
struct Stats {
    draws: atomic<u32>,
    triangles_lo: atomic<u32>,
    triangles_hi: atomic<u32>,
    boxes: atomic<u32>,
    drawn: array<atomic<u32>>,
}

// One binding number per resource across the entry points, so that no two
// variables share one.
@group(0) @binding(0) var<uniform> cull: Cull;
@group(0) @binding(1) var<storage, read> boxes: array<Box>;
@group(0) @binding(2) var<storage, read> src: ReadList;
@group(0) @binding(3) var<storage, read_write> flags: array<u32>;
@group(0) @binding(4) var<storage, read_write> raster: array<Box>;
@group(0) @binding(5) var<storage, read_write> box_draw: BoxDraw;
@group(0) @binding(6) var<storage, read> filter_flags: array<u32>;
@group(0) @binding(7) var<storage, read> unless_flags: array<u32>;
@group(0) @binding(8) var<storage, read_write> dst: WriteList;
@group(0) @binding(9) var<storage, read> ranges: array<vec2<u32>>;
@group(0) @binding(10) var<storage, read> items: array<u32>;
@group(0) @binding(11) var<storage, read> instances: array<InstanceDraw>;
@group(0) @binding(12) var<storage, read_write> draws: array<DrawArgs>;
@group(0) @binding(13) var<storage, read_write> stats: Stats;

// The box-test fragments' flags (the render pass's group 1).
@group(1) @binding(0) var<storage, read_write> box_flags: array<u32>;

const GROUP_SIZE: u32 = 64u;

fn thread_index(group: vec3<u32>, groups: vec3<u32>, local: u32) -> u32 {
    return (group.y * groups.x + group.x) * GROUP_SIZE + local;
}

// Entries of `src` to process.
fn src_len() -> u32 {
    return min(src.count, src.capacity);
}

// The p-vertex test against each plane, with a margin far above float
// rounding so that a box the rasterizer could draw is never called outside.
fn outside_frustum(b: Box) -> bool {
    let m = max(abs(b.lo), abs(b.hi));
    let scale = 1.0 + max(m.x, max(m.y, m.z));
    for (var i = 0u; i < 6u; i++) {
        let plane = cull.planes[i];
        let p = select(b.lo, b.hi, plane.xyz >= vec3<f32>(0.0));
        if dot(plane.xyz, p) + plane.w < -1e-5 * (scale + abs(plane.w)) {
            return true;
        }
    }
    return false;
}

// Box tests, first half: boxes near the eye are visible without drawing
// (they cannot be rasterized soundly), boxes outside the frustum hidden; the
// rest are appended to the raster list that the indirect box draw reads.
@compute @workgroup_size(64)
fn cs_test_boxes(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                 @builtin(local_invocation_index) local: u32) {
    let k = thread_index(group, groups, local);
    if k >= src_len() {
        return;
    }
    let b = boxes[src.ids[k]];
    // Empty boxes (min > max) hold nothing to see.
    if any(b.lo > b.hi) {
        return;
    }
    let gap = max(max(b.lo - cull.eye.xyz, cull.eye.xyz - b.hi), vec3<f32>(0.0));
    if dot(gap, gap) <= cull.eye.w {
        flags[b.id] = 1u;
        return;
    }
    if outside_frustum(b) {
        return;
    }
    // The append slot doubles as the instance index of the box draw.
    raster[atomicAdd(&box_draw.instance_count, 1u)] = b;
    atomicAdd(&stats.boxes, 1u);
}

// Box tests, second half: a fragment of the box that passed the depth test
// marks it visible. Forced early depth testing is what makes the test happen
// before the write: a shader with side effects otherwise runs (and writes)
// for fragments the depth test then discards.
@fragment @early_depth_test(force)
fn fs_test_box(@location(0) @interpolate(flat) id: u32) -> @location(0) vec4<f32> {
    box_flags[id] = 1u;
    return vec4<f32>(0.0);
}

// The range of entry k of `src`, when its flag in `filter_flags` is set.
fn expanded_range(k: u32) -> vec2<u32> {
    let id = src.ids[k];
    if filter_flags[id] == 0u {
        return vec2<u32>(0u, 0u);
    }
    return ranges[id];
}

// Expansion into a list: one atomic per entry reserves room for its whole
// range, written in order.
@compute @workgroup_size(64)
fn cs_expand_list(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                  @builtin(local_invocation_index) local: u32) {
    let k = thread_index(group, groups, local);
    if k >= src_len() {
        return;
    }
    let r = expanded_range(k);
    if r.y == 0u {
        return;
    }
    let base = atomicAdd(&dst.count, r.y);
    for (var j = 0u; j < r.y && base + j < dst.capacity; j++) {
        dst.ids[base + j] = items[r.x + j];
    }
}

@compute @workgroup_size(64)
fn cs_expand_flags(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                   @builtin(local_invocation_index) local: u32) {
    let k = thread_index(group, groups, local);
    if k >= src_len() {
        return;
    }
    let r = expanded_range(k);
    for (var j = 0u; j < r.y; j++) {
        flags[items[r.x + j]] = 1u;
    }
}

// Compaction: slot i joins `dst` when its flag is set (and, with `unless_flags`,
// its flag there is not).
fn compact_slot(i: u32, keep: bool) {
    if keep && filter_flags[i] != 0u {
        let slot = atomicAdd(&dst.count, 1u);
        if slot < dst.capacity {
            dst.ids[slot] = i;
        }
    }
}

@compute @workgroup_size(64)
fn cs_compact(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
              @builtin(local_invocation_index) local: u32) {
    let i = thread_index(group, groups, local);
    if i < arrayLength(&filter_flags) {
        compact_slot(i, true);
    }
}

@compute @workgroup_size(64)
fn cs_compact_unless(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                     @builtin(local_invocation_index) local: u32) {
    let i = thread_index(group, groups, local);
    if i < arrayLength(&filter_flags) {
        compact_slot(i, unless_flags[i] == 0u);
    }
}

// Frustum culling of flagged slots: a set flag whose box (slot for slot)
// lies outside the frustum is cleared, by the test cs_test_boxes uses.
@compute @workgroup_size(64)
fn cs_drop_outside(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                   @builtin(local_invocation_index) local: u32) {
    let i = thread_index(group, groups, local);
    if i >= arrayLength(&flags) || i >= arrayLength(&boxes) || flags[i] == 0u {
        return;
    }
    let b = boxes[i];
    if any(b.lo > b.hi) || outside_frustum(b) {
        flags[i] = 0u;
    }
}

// List draws: one indexed draw per listed instance, its first instance the
// instance index (vs_instance reads the transform there). Entries past the
// count become empty draws, so that without a count buffer a multi-draw over
// the whole capacity draws the same.
@compute @workgroup_size(64)
fn cs_draw_args(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                @builtin(local_invocation_index) local: u32) {
    let k = thread_index(group, groups, local);
    if k >= src.capacity {
        return;
    }
    let count = src_len();
    // One thread counts the draws; the others would all hit the same atomic.
    if k == 0u {
        atomicAdd(&stats.draws, count);
    }
    if k >= count {
        draws[k] = DrawArgs(0u, 0u, 0u, 0, 0u);
        return;
    }
    let i = src.ids[k];
    let m = instances[i];
    draws[k] = DrawArgs(m.index_count, 1u, m.first_index, m.base_vertex, i);
    // A 64-bit sum from 32-bit atomics: the low word wrapped when the old
    // value plus ours is smaller than ours, so carry one into the high word.
    let old = atomicAdd(&stats.triangles_lo, m.triangles);
    if old + m.triangles < m.triangles {
        atomicAdd(&stats.triangles_hi, 1u);
    }
    atomicOr(&stats.drawn[i / 32u], 1u << (i % 32u));
}
