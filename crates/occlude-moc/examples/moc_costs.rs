//! Measures the masked buffer's CPU costs that the soft backend's simulated
//! clock charges for `moc` (`cpu_moc_triangle_ns`, `cpu_moc_tile_ns`,
//! `cpu_moc_box_ns`, `cpu_moc_subtile_read_ns` in docs/gpu-models.md):
//! occluder triangles of several sizes are rendered and the time per call is
//! fitted as `a * triangles + b * tiles` by least squares; boxes of several
//! sizes and depths are tested against a filled buffer and the time per batch
//! is fitted as `a * boxes + b * subtiles read` the same way. Everything runs
//! on one thread, as the simulated clock charges it to the frame's one CPU
//! timeline (outside a pool of one thread, large calls would take the
//! parallel path on the machine's cores).
//!
//! `cargo run --release -p occlude-moc --example moc_costs`

use glam::{Mat4, Vec3};
use occlude_moc::{CullMode, MaskedBuffer};
use std::time::Instant;

const WIDTH: u32 = 1024;
const HEIGHT: u32 = 768;

/// A small deterministic generator (xorshift), so runs are repeatable.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// `count` counter-clockwise right triangles with legs of `legs` pixels at
/// random places and depths, as NDC positions and indices.
fn triangles(count: usize, legs: f32, rng: &mut Rng) -> (Vec<Vec3>, Vec<u32>) {
    let (sx, sy) = (2.0 * legs / WIDTH as f32, 2.0 * legs / HEIGHT as f32);
    let mut positions = Vec::with_capacity(count * 3);
    for _ in 0..count {
        let (x, y, z) = (rng.next() * (2.0 - sx) - 1.0, rng.next() * (2.0 - sy) - 1.0, 0.1 + 0.8 * rng.next());
        positions.extend([Vec3::new(x, y, z), Vec3::new(x + sx, y, z), Vec3::new(x, y + sy, z)]);
    }
    let indices = (0..positions.len() as u32).collect();
    (positions, indices)
}

/// The time of one call of `f`, in ns: calls are timed in batches of at
/// least 20 ms (so a short call is not lost in the clock's resolution or in
/// one interruption) and the fastest of `runs` batches is kept, after one
/// batch that is not timed (caches, page faults, clock frequency).
fn per_call_ns(runs: usize, mut f: impl FnMut()) -> f64 {
    let mut batch = |calls: u32| {
        let t = Instant::now();
        for _ in 0..calls {
            f();
        }
        t.elapsed().as_secs_f64() * 1e9
    };
    let mut calls = 1;
    while batch(calls) < 20e6 {
        calls *= 2;
    }
    (0..runs).map(|_| batch(calls) / calls as f64).fold(f64::INFINITY, f64::min)
}

/// Least squares for `y = a * u + b * v` over rows `(u, v, y)` (normal
/// equations).
fn fit(rows: &[(f64, f64, f64)]) -> (f64, f64) {
    let (mut uu, mut uv, mut vv, mut uy, mut vy) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for &(u, v, y) in rows {
        uu += u * u;
        uv += u * v;
        vv += v * v;
        uy += u * y;
        vy += v * y;
    }
    let det = uu * vv - uv * uv;
    ((uy * vv - vy * uv) / det, (vy * uu - uy * uv) / det)
}

fn main() {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("a pool of one thread");
    pool.install(measure);
}

/// Prints the per-call times and the two fits.
fn measure() {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let mut buffer = MaskedBuffer::new(WIDTH, HEIGHT).unwrap();
    // Rows of (triangles, tiles, ns) per call.
    let mut rows = Vec::new();
    println!("legs px  triangles  tiles/tri  ns/triangle");
    for legs in [2.0f32, 5.0, 10.0, 25.0, 50.0, 100.0, 250.0] {
        let count = (200_000.0 / (legs * legs)).clamp(200.0, 20_000.0) as usize;
        let (positions, indices) = triangles(count, legs, &mut rng);
        let mut work = Default::default();
        let ns = per_call_ns(5, || {
            buffer.clear();
            work = buffer.render_triangles(&positions, &indices, Mat4::IDENTITY, CullMode::Back);
        });
        let clear_ns = per_call_ns(5, || buffer.clear());
        let ns = ns - clear_ns;
        println!(
            "{legs:7}  {:9}  {:9.2}  {:11.1}",
            work.triangles,
            work.tiles as f64 / work.triangles as f64,
            ns / work.triangles as f64
        );
        rows.push((work.triangles as f64, work.tiles as f64, ns));
    }
    let (a, b) = fit(&rows);
    println!("fit: {a:.1} ns per triangle + {b:.1} ns per 32x8 tile");

    // Boxes against a buffer full of mid-sized occluders at mid depth.
    let (positions, indices) = triangles(20_000, 50.0, &mut rng);
    buffer.clear();
    buffer.render_triangles(&positions, &indices, Mat4::IDENTITY, CullMode::Back);
    // Rows of (boxes, subtiles read, ns) per batch of boxes.
    let mut rows = Vec::new();
    println!("box px  depth  reads/box  ns/box");
    for size in [4.0, 16.0, 64.0, 256.0] {
        let (dx, dy) = (2.0 * size / WIDTH as f32, 2.0 * size / HEIGHT as f32);
        let boxes: Vec<(Vec3, Vec3)> = (0..2000)
            .map(|_| {
                let (x, y) = (rng.next() * (2.0 - dx) - 1.0, rng.next() * (2.0 - dy) - 1.0);
                (Vec3::new(x, y, 0.0), Vec3::new(x + dx, y + dy, 0.0))
            })
            .collect();
        // Behind every occluder, among them, and in front of them.
        for z in [0.95f32, 0.5, 0.05] {
            let test = |lo: &Vec3, hi: &Vec3| {
                buffer.test_aabb_counted(Vec3::new(lo.x, lo.y, z), Vec3::new(hi.x, hi.y, z + 0.01), Mat4::IDENTITY)
            };
            let reads: u64 = boxes.iter().map(|(lo, hi)| test(lo, hi).1).sum();
            let ns = per_call_ns(5, || {
                for (lo, hi) in &boxes {
                    std::hint::black_box(test(lo, hi));
                }
            });
            let n = boxes.len() as f64;
            println!("{size:6}  {z:5}  {:9.1}  {:6.1}", reads as f64 / n, ns / n);
            rows.push((n, reads as f64, ns));
        }
    }
    let (a, b) = fit(&rows);
    println!("fit: {a:.1} ns per box + {b:.2} ns per subtile read");
}
