// The embedding's draw commands (embed/draws.rs): a visible list sorted into
// buckets, one per (draw group, mesh) pair, each bucket one indirect draw of
// its mesh; then the buckets that drew something packed per group, for
// multi-draws with a count. One thread per list entry or bucket, in
// workgroups of 64 laid out in two dimensions, as cull.wgsl's.

// The visible list as cull.wgsl's compaction wrote it.
struct ReadList {
    count: u32,
    capacity: u32,
    ids: array<u32>,
}

// Words per command (5 indexed, 4 not) and the number of buckets.
struct Layout {
    stride: u32,
    buckets: u32,
}

@group(0) @binding(0) var<storage, read> list: ReadList;
// Each instance's bucket.
@group(0) @binding(1) var<storage, read> instance_bucket: array<u32>;
// One command per bucket: its mesh's words, the instance count counted up
// here from zero, the first instance the bucket's first slot in `sorted`.
@group(0) @binding(2) var<storage, read_write> commands: array<atomic<u32>>;
// The renderer's list: count, capacity, then the ids bucket by bucket. The
// vertex shader reads ids[instance_index], since instance_index counts from
// the command's first instance.
@group(0) @binding(3) var<storage, read_write> sorted: array<u32>;
@group(0) @binding(4) var<uniform> shape: Layout;
@group(0) @binding(5) var<storage, read> bucket_group: array<u32>;
// Per group: the commands packed so far, and where its packed commands start.
@group(0) @binding(6) var<storage, read_write> group_counts: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read> group_first: array<u32>;
@group(0) @binding(8) var<storage, read_write> packed: array<u32>;

const GROUP_SIZE: u32 = 64u;

fn thread_index(group: vec3<u32>, groups: vec3<u32>, local: u32) -> u32 {
    return (group.y * groups.x + group.x) * GROUP_SIZE + local;
}

// Entry k of the list joins its instance's bucket: one atomic on the
// bucket's instance count reserves its slot.
@compute @workgroup_size(64)
fn cs_sort_list(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                @builtin(local_invocation_index) local: u32) {
    let k = thread_index(group, groups, local);
    let count = min(list.count, list.capacity);
    if k == 0u {
        sorted[0] = count;
    }
    if k >= count {
        return;
    }
    let i = list.ids[k];
    let command = instance_bucket[i] * shape.stride;
    let slot = atomicAdd(&commands[command + 1u], 1u);
    let first = atomicLoad(&commands[command + shape.stride - 1u]);
    sorted[2u + first + slot] = i;
}

// Bucket b's command, if it draws any instance, is copied to the next free
// place of its group's run in `packed`.
@compute @workgroup_size(64)
fn cs_pack_commands(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                    @builtin(local_invocation_index) local: u32) {
    let b = thread_index(group, groups, local);
    if b >= shape.buckets {
        return;
    }
    let src = b * shape.stride;
    if atomicLoad(&commands[src + 1u]) == 0u {
        return;
    }
    let g = bucket_group[b];
    let dst = (group_first[g] + atomicAdd(&group_counts[g], 1u)) * shape.stride;
    for (var w = 0u; w < shape.stride; w++) {
        packed[dst + w] = atomicLoad(&commands[src + w]);
    }
}
