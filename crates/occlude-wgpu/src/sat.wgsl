// Summed-area-table queries on the GPU (Engelhardt and Dachsbacher,
// section 3.1): objects drawn into colour targets with the channel of
// their region-set rectangle holding each pixel, the summed area table
// of every channel by prefix sums (rows, then columns, exact u32 sums),
// and each object's count from four reads per lookup. The colour targets'
// count is set by the Rust side (`sat.rs`), which puts the colour
// outputs and the colour textures where the two `//@` lines are. Bindings
// are unique across the module; each entry point's layout holds the ones
// it uses.

struct Lookup {
    x0: u32, y0: u32, x1: u32, y1: u32,
    channel: u32, _p0: u32, _p1: u32, _p2: u32,
}

struct Size {
    width: u32,
    height: u32,
    channels: u32,
    objects: u32,
}

@group(0) @binding(0) var<storage, read> lookups: array<Lookup>;
// Per object, its lookups: first and count.
@group(0) @binding(1) var<storage, read> ranges: array<vec2<u32>>;

struct Shaded {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) object: u32,
}

@vertex
fn vs(@location(0) p: vec4<f32>, @location(1) object: u32) -> Shaded {
    return Shaded(p, object);
}

// The channel object `object` renders pixel (x, y) in (none: 0xffffffff).
fn channel_at(object: u32, x: u32, y: u32) -> u32 {
    let r = ranges[object];
    for (var i = r.x; i < r.x + r.y; i++) {
        let l = lookups[i];
        if (x >= l.x0 && x < l.x1 && y >= l.y0 && y < l.y1) {
            return l.channel;
        }
    }
    return 0xffffffffu;
}

// One-hot colour of `channel` in target `colour_target`.
fn one_hot(channel: u32, colour_target: u32) -> vec4<f32> {
    let hit = vec4<u32>(colour_target * 4u) + vec4<u32>(0u, 1u, 2u, 3u) == vec4<u32>(channel);
    return select(vec4<f32>(0.0), vec4<f32>(1.0), hit);
}

//@COLOURS

@group(0) @binding(2) var<storage, read_write> sums: array<u32>;
@group(0) @binding(3) var<uniform> size: Size;
@group(0) @binding(4) var<storage, read_write> counts: array<u32>;

//@TEXTURES

// Pixels of `channel` left of and above grid point (x, y) go at index
// channel * (w + 1) * (h + 1) + y * (w + 1) + x.
fn at(channel: u32, x: u32, y: u32) -> u32 {
    return channel * (size.width + 1u) * (size.height + 1u) + y * (size.width + 1u) + x;
}

// One invocation per row and channel: the row's prefix sums.
@compute @workgroup_size(64)
fn rows(@builtin(global_invocation_id) id: vec3<u32>) {
    let y = id.x;
    let channel = id.y;
    if (y >= size.height || channel >= size.channels) {
        return;
    }
    var sum = 0u;
    for (var x = 0u; x < size.width; x++) {
        sum += texel(channel, x, y);
        sums[at(channel, x + 1u, y + 1u)] = sum;
    }
}

// One invocation per grid column and channel: the column's prefix sums
// of the row sums.
@compute @workgroup_size(64)
fn columns(@builtin(global_invocation_id) id: vec3<u32>) {
    let x = id.x;
    let channel = id.y;
    if (x > size.width || channel >= size.channels) {
        return;
    }
    var sum = 0u;
    for (var y = 1u; y <= size.height; y++) {
        sum += sums[at(channel, x, y)];
        sums[at(channel, x, y)] = sum;
    }
}

// One invocation per object: the sum of its lookups, four reads each
// (a + d - b - c wraps in u32 to the exact non-negative count).
@compute @workgroup_size(64)
fn count(@builtin(global_invocation_id) id: vec3<u32>) {
    let object = id.x;
    if (object >= size.objects) {
        return;
    }
    let r = ranges[object];
    var total = 0u;
    for (var i = r.x; i < r.x + r.y; i++) {
        let l = lookups[i];
        let c = l.channel;
        total += sums[at(c, l.x1, l.y1)] + sums[at(c, l.x0, l.y0)] - sums[at(c, l.x0, l.y1)] - sums[at(c, l.x1, l.y0)];
    }
    counts[object] = total;
}
