// Scene and query-proxy shaders of the wgpu backend.
//
// Instances are drawn from one vertex/index pool, their world transforms read
// from a storage buffer at `instance_index` (the draw's first instance).
// Query boxes are one draw of 36 corner indices per multi-query, one instance
// per box. GPU-resident culling reuses both: its box tests are query boxes
// whose fragments set flags (cull.wgsl), its list draws are instance draws
// whose colour is read per instance.

struct Camera {
    view_projection: mat4x4<f32>,
    // x: depth bias of query boxes (normalized device depth), see
    // occlude_core::query_box::QUERY_DEPTH_BIAS.
    query: vec4<f32>,
}

struct QueryBox {
    lo: vec3<f32>,
    // Box tests: the slot whose flag the box's fragments set (0 for queries).
    id: u32,
    hi: vec3<f32>,
}

@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var<storage, read> transforms: array<mat4x4<f32>>;
@group(0) @binding(2) var<storage, read> boxes: array<QueryBox>;
@group(1) @binding(0) var<uniform> material_color: vec4<f32>;
// List draws: every instance's material colour (binding 1, so that no
// binding of this module is declared twice).
@group(1) @binding(1) var<storage, read> instance_colors: array<vec4<f32>>;

struct Shaded {
    // Invariant: the drawing pipeline, the oracle's depth-equal pipeline and
    // the list draws must compute bit-identical depths for the same instance.
    @builtin(position) @invariant clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) @interpolate(flat) instance: u32,
}

@vertex
fn vs_instance(@location(0) position: vec3<f32>, @builtin(instance_index) instance: u32) -> Shaded {
    let world = transforms[instance] * vec4<f32>(position, 1.0);
    var out: Shaded;
    out.clip = camera.view_projection * world;
    out.world = world.xyz;
    out.instance = instance;
    return out;
}

// Flat shading from the screen-space derivatives of the world position: the
// meshes carry no normals and the colour only helps a person see the scene.
fn shade(world: vec3<f32>, color: vec4<f32>) -> vec4<f32> {
    let n = normalize(cross(dpdx(world), dpdy(world)));
    let light = 0.35 + 0.65 * abs(dot(n, normalize(vec3<f32>(0.4, 0.8, 0.3))));
    return vec4<f32>(color.rgb * light, 1.0);
}

@fragment
fn fs_shaded(in: Shaded) -> @location(0) vec4<f32> {
    return shade(in.world, material_color);
}

@fragment
fn fs_listed(in: Shaded) -> @location(0) vec4<f32> {
    return shade(in.world, instance_colors[in.instance]);
}

struct BoxVertex {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) id: u32,
}

@vertex
fn vs_query_box(@builtin(vertex_index) corner: u32, @builtin(instance_index) index: u32) -> BoxVertex {
    let b = boxes[index];
    let pick_max = vec3<bool>((corner & 1u) != 0u, (corner & 2u) != 0u, (corner & 4u) != 0u);
    let c = camera.view_projection * vec4<f32>(select(b.lo, b.hi, pick_max), 1.0);
    return BoxVertex(vec4<f32>(c.x, c.y, c.z - camera.query.x * c.w, c.w), b.id);
}

// Queries and the oracle write no colour (the write mask is empty); the pass
// has a colour target, so their pipelines still need a fragment stage.
@fragment
fn fs_none() -> @location(0) vec4<f32> {
    return vec4<f32>(0.0);
}
