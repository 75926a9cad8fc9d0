// The fragment stages of GPU-resident culling's box tests and counted
// queries, appended to cull.wgsl (culling.rs): they need early depth tests
// (SHADER_EARLY_DEPTH_TEST), which the compute passes alone do not.

// The box-test fragments' flags (the render pass's group 1).
@group(1) @binding(0) var<storage, read_write> box_flags: array<u32>;
// Counted queries (`--queries hib`): per query slot a 64-bit count of its
// boxes' fragments that passed the depth test, low word first.
@group(1) @binding(2) var<storage, read_write> query_counts: array<atomic<u32>>;

// Box tests, second half: a fragment of the box that passed the depth test
// marks it visible. Forced early depth testing is what makes the test happen
// before the write: a shader with side effects otherwise runs (and writes)
// for fragments the depth test then discards.
@fragment @early_depth_test(force)
fn fs_test_box(@location(0) @interpolate(flat) id: u32) -> @location(0) vec4<f32> {
    box_flags[id] = 1u;
    return vec4<f32>(0.0);
}

// Counted queries: a fragment of a query's box that passed the depth test
// (forced early, as for box tests) adds one to the query's count, carrying
// into the high word. Boxes of one query or of several may overlap: each
// fragment counts, as a hardware occlusion query counts them.
@fragment @early_depth_test(force)
fn fs_count_box(@location(0) @interpolate(flat) slot: u32) -> @location(0) vec4<f32> {
    if atomicAdd(&query_counts[2u * slot], 1u) == 0xffffffffu {
        atomicAdd(&query_counts[2u * slot + 1u], 1u);
    }
    return vec4<f32>(0.0);
}
