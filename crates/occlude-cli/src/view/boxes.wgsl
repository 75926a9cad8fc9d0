// Query boxes of the CHC paper's Figure 4: translucent faces and opaque
// outlines, coloured per vertex, drawn over the finished frame with no depth
// test (hidden boxes are the point).

@group(0) @binding(0) var<uniform> view_projection: mat4x4<f32>;

struct Coloured {
    @builtin(position) clip: vec4<f32>,
    @location(0) color: vec4<f32>,
}

@vertex
fn vs_box(@location(0) position: vec3<f32>, @location(1) color: vec4<f32>) -> Coloured {
    var out: Coloured;
    out.clip = view_projection * vec4<f32>(position, 1.0);
    out.color = color;
    return out;
}

@fragment
fn fs_box(in: Coloured) -> @location(0) vec4<f32> {
    return in.color;
}
