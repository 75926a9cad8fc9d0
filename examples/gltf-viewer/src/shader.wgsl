// The viewer's own shader: every mesh of the scene in one vertex and index
// buffer, each instance's transform and base colour in a storage buffer,
// flat shading (the face normal from screen-space derivatives, turned to
// the eye) under one directional light. Surfaces of different materials
// at the same depth (walls touching) would show whichever was drawn
// first, and culling changes the order: each fragment's depth is pushed
// farther by its material's id modulo 8 in units of the last place, so
// that the nearer material wins whatever the order. Farther depth keeps
// occlusion culling conservative.

struct Uniforms {
    view_projection: mat4x4<f32>,
    eye: vec4<f32>,
}

struct Instance {
    transform: mat4x4<f32>,
    // The base colour, then the material id.
    color: vec4<f32>,
}

@group(0) @binding(0) var<uniform> uniforms: Uniforms;
@group(0) @binding(1) var<storage, read> instances: array<Instance>;

struct Shaded {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) @interpolate(flat) color: vec4<f32>,
}

// Mesh vertex `position` of instance `i`, placed.
fn place(position: vec3<f32>, i: u32) -> Shaded {
    let instance = instances[i];
    let world = instance.transform * vec4<f32>(position, 1.0);
    return Shaded(uniforms.view_projection * world, world.xyz, instance.color);
}

// Drawing instances one by one: the instance index is the instance.
@vertex
fn vs_main(@location(0) position: vec3<f32>, @builtin(instance_index) i: u32) -> Shaded {
    return place(position, i);
}

// Drawing a list of occlude's GPU-driven culling (its bind group made by
// occlude): the instance index is a place in the list.
struct VisibleList {
    count: u32,
    capacity: u32,
    ids: array<u32>,
}

@group(1) @binding(0) var<storage, read> visible: VisibleList;

@vertex
fn vs_listed(@location(0) position: vec3<f32>, @builtin(instance_index) k: u32) -> Shaded {
    return place(position, visible.ids[k]);
}

struct Fragment {
    @location(0) color: vec4<f32>,
    @builtin(frag_depth) depth: f32,
}

@fragment
fn fs_main(in: Shaded) -> Fragment {
    var normal = normalize(cross(dpdx(in.world), dpdy(in.world)));
    if dot(normal, uniforms.eye.xyz - in.world) < 0.0 {
        normal = -normal;
    }
    let light = 0.55 + 0.45 * max(dot(normal, normalize(vec3<f32>(0.4, 0.8, 0.45))), 0.0);
    let depth = bitcast<f32>(bitcast<u32>(in.clip.z) + u32(in.color.a) % 8u);
    return Fragment(vec4<f32>(in.color.rgb * light, 1.0), depth);
}
