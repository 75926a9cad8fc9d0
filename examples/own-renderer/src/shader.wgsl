// The example renderer's own shader: a mesh in the unit box per instance,
// moved and scaled by per-instance attributes, lit by one directional light,
// in one of two shadings (the renderer's two draw groups).

struct Uniforms {
    view_projection: mat4x4<f32>,
}

@group(0) @binding(0) var<uniform> uniforms: Uniforms;

struct Vertex {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) offset: vec3<f32>,
    @location(3) scale: vec3<f32>,
    @location(4) color: vec3<f32>,
}

struct Shaded {
    @builtin(position) clip: vec4<f32>,
    @location(0) color: vec3<f32>,
}

// A mesh vertex of an instance, placed and lit.
fn shade(v: Vertex) -> Shaded {
    let world = v.offset + v.scale * v.position;
    let light = 0.35 + 0.65 * max(dot(v.normal, normalize(vec3<f32>(0.3, 0.9, 0.5))), 0.0);
    return Shaded(uniforms.view_projection * vec4<f32>(world, 1.0), v.color * light);
}

@vertex
fn vs_main(v: Vertex) -> Shaded {
    return shade(v);
}

@fragment
fn fs_main(in: Shaded) -> @location(0) vec4<f32> {
    return vec4<f32>(in.color, 1.0);
}

// The second shading: the colour's channels turned round.
@fragment
fn fs_tinted(in: Shaded) -> @location(0) vec4<f32> {
    return vec4<f32>(in.color.bgr, 1.0);
}

// Drawing a list of visible instances written by occlude's GPU-driven
// culling (`occlude::wgpu::embed::VisibleList`, in group 1, whose bind
// group occlude makes): one indirect draw, the instance id read from the
// list, the instance from a storage buffer of the same rows as the
// instance vertex buffer (offset, scale, colour).

struct VisibleList {
    count: u32,
    capacity: u32,
    ids: array<u32>,
}

@group(0) @binding(1) var<storage, read> instances: array<f32>;
@group(1) @binding(0) var<storage, read> visible: VisibleList;

struct MeshVertex {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
}

// Three floats of the instance row starting at `at`.
fn instance_field(at: u32) -> vec3<f32> {
    return vec3<f32>(instances[at], instances[at + 1u], instances[at + 2u]);
}

@vertex
fn vs_listed(v: MeshVertex, @builtin(instance_index) k: u32) -> Shaded {
    let row = 9u * visible.ids[k];
    return shade(Vertex(v.position, v.normal, instance_field(row), instance_field(row + 3u), instance_field(row + 6u)));
}
