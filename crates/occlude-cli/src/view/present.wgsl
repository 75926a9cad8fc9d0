// The viewer's image blit: one triangle covering the viewport, sampling an
// image with (0, 0) at its top-left corner.

@group(0) @binding(0) var image: texture_2d<f32>;
@group(0) @binding(1) var image_sampler: sampler;

struct Covered {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
}

@vertex
fn vs_cover(@builtin(vertex_index) corner: u32) -> Covered {
    // Corners (0, 0), (2, 0), (0, 2) in uv: the triangle holds the square.
    let uv = vec2<f32>(f32((corner << 1u) & 2u), f32(corner & 2u));
    var out: Covered;
    out.clip = vec4<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0, 0.0, 1.0);
    out.uv = uv;
    return out;
}

@fragment
fn fs_image(in: Covered) -> @location(0) vec4<f32> {
    return textureSample(image, image_sampler, in.uv);
}
