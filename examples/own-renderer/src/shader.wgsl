// The example renderer's own shader: a unit cube per instance, moved and
// scaled by per-instance attributes, lit by one directional light.

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

@vertex
fn vs_main(v: Vertex) -> Shaded {
    let world = v.offset + v.scale * v.position;
    let light = 0.35 + 0.65 * max(dot(v.normal, normalize(vec3<f32>(0.3, 0.9, 0.5))), 0.0);
    return Shaded(uniforms.view_projection * vec4<f32>(world, 1.0), v.color * light);
}

@fragment
fn fs_main(in: Shaded) -> @location(0) vec4<f32> {
    return vec4<f32>(in.color, 1.0);
}
