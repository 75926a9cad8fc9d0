// The hierarchical item buffer (item_buffer.rs; Engelhardt and Dachsbacher
// 2009, section 3.2): an item pass drawing each object's instances with one
// instanced draw, writing per pixel the item ID of the nearest fragment,
// then a histogram of the IDs with atomics and its reduction to per-slot,
// per-object and per-tile totals.

struct Camera {
    view_projection: mat4x4<f32>,
    query: vec4<f32>,
}

// The pass's constants: image size, tile level t, pixels, bins, and where
// the object and tile totals start in `totals`.
struct Pass {
    width: u32,
    height: u32,
    level: u32,
    pixels: u32,
    bins: u32,
    objects_at: u32,
    tiles_at: u32,
}

// One binding number per resource across the entry points.
@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var<storage, read> transforms: array<mat4x4<f32>>;
// The scene instance of each slot (instance_index of the instanced draws).
@group(0) @binding(2) var<storage, read> slots: array<u32>;
@group(0) @binding(3) var<uniform> pass_info: Pass;
@group(0) @binding(4) var items: texture_2d<u32>;
// The pixels in a scrambled order: neighbours, which often hold the same ID,
// go to different threads (the paper's reordering against atomic contention).
@group(0) @binding(5) var<storage, read> order: array<u32>;
@group(0) @binding(6) var<storage, read_write> bins: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read> slot_object: array<u32>;
@group(0) @binding(8) var<storage, read_write> totals: array<atomic<u32>>;

const GROUP_SIZE: u32 = 64u;

struct ItemVertex {
    // Invariant, as the scene shaders' draws: the item pass's depths are
    // bit-identical to theirs.
    @builtin(position) @invariant clip: vec4<f32>,
    @location(0) @interpolate(flat) slot: u32,
}

@vertex
fn vs_item(@location(0) position: vec3<f32>, @builtin(instance_index) slot: u32) -> ItemVertex {
    let world = transforms[slots[slot]] * vec4<f32>(position, 1.0);
    var out: ItemVertex;
    out.clip = camera.view_projection * world;
    out.slot = slot;
    return out;
}

// ID = slot * 2^(2t) + x + y * 2^t, (x, y) the pixel's tile.
@fragment
fn fs_item(in: ItemVertex) -> @location(0) u32 {
    let p = vec2<u32>(in.clip.xy);
    let level = pass_info.level;
    let tile = vec2<u32>((p.x << level) / pass_info.width, (p.y << level) / pass_info.height);
    return (in.slot << (2u * level)) + tile.x + (tile.y << level);
}

fn thread_index(group: vec3<u32>, groups: vec3<u32>, local: u32) -> u32 {
    return (group.y * groups.x + group.x) * GROUP_SIZE + local;
}

// One thread per pixel: its ID's bin counts one more.
@compute @workgroup_size(64)
fn cs_histogram(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                @builtin(local_invocation_index) local: u32) {
    let k = thread_index(group, groups, local);
    if k >= pass_info.pixels {
        return;
    }
    let p = order[k];
    let id = textureLoad(items, vec2<u32>(p % pass_info.width, p / pass_info.width), 0).x;
    if id < pass_info.bins {
        atomicAdd(&bins[id], 1u);
    }
}

// One thread per bin: its count added to its slot's, object's and tile's
// totals (the paper's mip levels, summed directly).
@compute @workgroup_size(64)
fn cs_reduce(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
             @builtin(local_invocation_index) local: u32) {
    let b = thread_index(group, groups, local);
    if b >= pass_info.bins {
        return;
    }
    let count = atomicLoad(&bins[b]);
    if count == 0u {
        return;
    }
    let slot = b >> (2u * pass_info.level);
    let tile = b & ((1u << (2u * pass_info.level)) - 1u);
    atomicAdd(&totals[slot], count);
    atomicAdd(&totals[pass_info.objects_at + slot_object[slot]], count);
    atomicAdd(&totals[pass_info.tiles_at + tile], count);
}
