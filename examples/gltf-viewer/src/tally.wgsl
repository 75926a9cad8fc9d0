// The viewer's instrument for its overlay: the instances and triangles a
// visible list of occlude's GPU-driven culling draws, summed on the GPU
// from the list's indexed draw commands (index count, instance count,
// first index, base vertex, first instance).

@group(0) @binding(0) var<storage, read> commands: array<u32>;
// Instances, then triangles.
@group(0) @binding(1) var<storage, read_write> totals: array<atomic<u32>, 2>;

@compute @workgroup_size(64)
fn cs_tally(@builtin(global_invocation_id) id: vec3<u32>) {
    let command = 5u * id.x;
    if command + 5u <= arrayLength(&commands) {
        let instances = commands[command + 1u];
        atomicAdd(&totals[0], instances);
        atomicAdd(&totals[1], instances * (commands[command] / 3u));
    }
}
