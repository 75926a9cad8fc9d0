// GPU-resident culling (culling.rs): compute passes over id lists and flag
// buffers. The fragment stage of the batched box tests (whose vertex stage
// is vs_query_box of shader.wgsl) is in cull_fragments.wgsl, appended to
// this file where the device has early depth tests; the embedding's
// compute passes (embed/gpu_culler.rs) use this file alone.
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

// The camera of the frame: the six frustum planes (inside: n.p + d >= 0), the
// eye, its w the squared near-region radius (Camera::box_touches_near_region),
// the view-projection matrix, and depth_pyramid's constants: the query depth
// bias, the depth slack and the pixel margin.
struct Cull {
    planes: array<vec4<f32>, 6>,
    eye: vec4<f32>,
    view_projection: mat4x4<f32>,
    bias: f32,
    depth_slack: f32,
    pixel_margin: f32,
}

// A depth-pyramid level in `pyramid`: its first texel, width, height and row
// pitch (level 0, copied from the depth texture, has rows padded for the copy).
struct Level {
    offset: u32,
    width: u32,
    height: u32,
    pitch: u32,
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
@group(0) @binding(14) var<storage, read_write> pyramid: array<f32>;
@group(0) @binding(15) var<storage, read> levels: array<Level>;
// The level a reduction writes, the reach of a pyramid test, or for a
// pyramid's level 0 read from a depth texture (1 or 0) whether it is reverse
// Z and the viewport's corner (.yz).
@group(0) @binding(16) var<uniform> param: vec4<u32>;
// A renderer's depth texture (the embedding's pyramids are built from it),
// single-sample or multisampled.
@group(0) @binding(17) var depth_texture: texture_depth_2d;
@group(0) @binding(18) var depth_samples: texture_depth_multisampled_2d;


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

// The frustum and near rules of box tests: entry k of `src` is to be tested
// when its box is not empty, not near the eye (flagged visible here without a
// test, as it cannot be rasterized soundly) and not outside the frustum.
fn box_to_test(k: u32) -> bool {
    let b = boxes[src.ids[k]];
    // Empty boxes (min > max) hold nothing to see.
    if any(b.lo > b.hi) {
        return false;
    }
    let gap = max(max(b.lo - cull.eye.xyz, cull.eye.xyz - b.hi), vec3<f32>(0.0));
    if dot(gap, gap) <= cull.eye.w {
        flags[b.id] = 1u;
        return false;
    }
    return !outside_frustum(b);
}

// Box tests, first half: the boxes to test are appended to the raster list
// that the indirect box draw reads.
@compute @workgroup_size(64)
fn cs_test_boxes(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                 @builtin(local_invocation_index) local: u32) {
    let k = thread_index(group, groups, local);
    if k >= src_len() || !box_to_test(k) {
        return;
    }
    // The append slot doubles as the instance index of the box draw.
    raster[atomicAdd(&box_draw.instance_count, 1u)] = boxes[src.ids[k]];
    atomicAdd(&stats.boxes, 1u);
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

// Depth-pyramid reduction of level param.x (depth_pyramid.rs): texel (x, y)
// is the maximum of the texels (2x + i, 2y + j) of the level before that
// exist, one thread per texel.
@compute @workgroup_size(64)
fn cs_pyramid_level(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                    @builtin(local_invocation_index) local: u32) {
    let t = thread_index(group, groups, local);
    let dst_level = levels[param.x];
    if t >= dst_level.width * dst_level.height {
        return;
    }
    let src_level = levels[param.x - 1u];
    let x = t % dst_level.width;
    let y = t / dst_level.width;
    var farthest = 0.0;
    for (var sy = 2u * y; sy < min(2u * y + 2u, src_level.height); sy++) {
        for (var sx = 2u * x; sx < min(2u * x + 2u, src_level.width); sx++) {
            farthest = max(farthest, pyramid[src_level.offset + sy * src_level.pitch + sx]);
        }
    }
    pyramid[dst_level.offset + y * dst_level.pitch + x] = farthest;
}

// How much farther than the depth texture's value level 0 of an embedded
// pyramid is taken: 2^-22, four steps of a 24-bit depth buffer (whose stored
// depth is the fragment's rounded to one), more than the rounding of
// 1 - depth for reverse Z (half a step of f32 at 1).
const LOAD_SLACK: f32 = 2.384185791015625e-7;

// Level 0 of a depth pyramid from a renderer's depth texture (the
// embedding's): each texel its pixel's depth (in the viewport at param.yz),
// turned into depth 0 nearest when param.x says the texture is reverse Z, and
// pushed LOAD_SLACK farther, so that it is never nearer than the depth the
// renderer's fragments had.
fn base_texel(depth: f32) -> f32 {
    return min(select(depth, 1.0 - depth, param.x != 0u) + LOAD_SLACK, 1.0);
}

// Level 0's texel of thread t: (x, y, index), or x past the level's width.
fn base_slot(t: u32) -> vec3<u32> {
    let level = levels[0];
    if t >= level.width * level.height {
        return vec3<u32>(level.width, 0u, 0u);
    }
    let x = t % level.width;
    let y = t / level.width;
    return vec3<u32>(x, y, level.offset + y * level.pitch + x);
}

@compute @workgroup_size(64)
fn cs_pyramid_base(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                   @builtin(local_invocation_index) local: u32) {
    let slot = base_slot(thread_index(group, groups, local));
    if slot.x < levels[0].width {
        pyramid[slot.z] = base_texel(textureLoad(depth_texture, slot.xy + param.yz, 0));
    }
}

// With MSAA a texel is the farthest of its pixel's samples, so that it is
// never nearer than any sample an instance may show at.
@compute @workgroup_size(64)
fn cs_pyramid_base_samples(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                           @builtin(local_invocation_index) local: u32) {
    let slot = base_slot(thread_index(group, groups, local));
    if slot.x >= levels[0].width {
        return;
    }
    var farthest = 0.0;
    for (var s = 0u; s < textureNumSamples(depth_samples); s++) {
        farthest = max(farthest, base_texel(textureLoad(depth_samples, slot.xy + param.yz, s)));
    }
    pyramid[slot.z] = farthest;
}

// A bound on how far two f32 evaluations of a sum or quotient may differ,
// relative to the magnitudes involved (16 units in the last place).
const ROUNDING: f32 = 1.0 / 1048576.0;

// depth_pyramid::box_footprint of a box, on the GPU: the pixel range
// (x0, y0, x1, y1) of its corners' projection and its nearest depth, or
// `near` when a corner is on or behind the near plane, or `empty` when the
// range holds no pixel centre. The CPU divides in f64 and the GPU in f32,
// and their products may round differently; each corner's projection is
// grown, and its depth lowered, by a bound on that difference (ROUNDING of
// the magnitudes summed, carried through the division to first order), so
// the range here contains the CPU's and the depth is no greater.
struct Footprint {
    near: bool,
    empty: bool,
    lo: vec2<u32>,
    hi: vec2<u32>,
    depth: f32,
}

fn box_footprint(b: Box, size: vec2<f32>) -> Footprint {
    var out = Footprint(false, false, vec2<u32>(0u), vec2<u32>(0u), 0.0);
    let m = cull.view_projection;
    var lo = vec2<f32>(3.0e38);
    var hi = vec2<f32>(-3.0e38);
    var depth = 3.0e38;
    for (var c = 0u; c < 8u; c++) {
        let p = vec4<f32>(select(b.lo, b.hi, (vec3<u32>(c) & vec3<u32>(1u, 2u, 4u)) != vec3<u32>(0u)), 1.0);
        let v = m * p;
        let z = v.z - cull.bias * v.w;
        // Written so that NaN counts as reaching the near plane.
        if !(z > 0.0 && v.w > 0.0) {
            out.near = true;
            return out;
        }
        // The magnitudes summed into each clip coordinate.
        let a = abs(m[0]) * abs(p.x) + abs(m[1]) * abs(p.y) + abs(m[2]) * abs(p.z) + abs(m[3]);
        let ndc = v.xy / v.w;
        let s = vec2<f32>((ndc.x + 1.0) * 0.5 * size.x, (1.0 - ndc.y) * 0.5 * size.y);
        let error = (ROUNDING * (a.xy + abs(ndc) * a.w) / v.w + ROUNDING * (abs(ndc) + 1.0)) * size;
        lo = min(lo, s - error);
        hi = max(hi, s + error);
        let d = z / v.w;
        let depth_error = ROUNDING * (a.z + cull.bias * a.w + abs(d) * a.w) / v.w + ROUNDING * abs(d);
        depth = min(depth, d - depth_error);
    }
    // Pixel p is covered only if its centre p + 0.5 is in [lo, hi].
    let first = max(ceil(lo - 0.5 - cull.pixel_margin), vec2<f32>(0.0));
    let last = min(floor(hi - 0.5 + cull.pixel_margin), size - 1.0);
    if !(first.x <= last.x && first.y <= last.y) {
        out.empty = true;
        return out;
    }
    out.lo = vec2<u32>(first);
    out.hi = vec2<u32>(last);
    out.depth = depth - cull.depth_slack;
    return out;
}

// Pyramid box tests (DepthPyramid::test): the rules of box tests, then each
// remaining box's footprint against the finest level at which it spans at
// most param.x texels per axis; visible when its nearest depth is in front of
// the farthest of them.
@compute @workgroup_size(64)
fn cs_test_boxes_pyramid(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                         @builtin(local_invocation_index) local: u32) {
    let k = thread_index(group, groups, local);
    if k >= src_len() || !box_to_test(k) {
        return;
    }
    atomicAdd(&stats.boxes, 1u);
    let b = boxes[src.ids[k]];
    let f = box_footprint(b, vec2<f32>(f32(levels[0].width), f32(levels[0].height)));
    if f.near {
        flags[b.id] = 1u;
        return;
    }
    if f.empty {
        return;
    }
    // A reach of 0 is read as 1, which ends the level search too.
    let reach = max(param.x, 1u);
    var level = 0u;
    while (f.hi.x >> level) - (f.lo.x >> level) >= reach || (f.hi.y >> level) - (f.lo.y >> level) >= reach {
        level++;
    }
    let l = levels[level];
    var farthest = 0.0;
    for (var y = f.lo.y >> level; y <= f.hi.y >> level; y++) {
        for (var x = f.lo.x >> level; x <= f.hi.x >> level; x++) {
            farthest = max(farthest, pyramid[l.offset + y * l.pitch + x]);
        }
    }
    if f.depth < farthest {
        flags[b.id] = 1u;
    }
}
