//! Which meshes of a generated scene get an inner box (`moc.proxies`): per
//! scene, meshes, meshes with a box, and the boxes' volume as a fraction of
//! the mesh's bounding box, weighted by instances.
//!
//! `cargo run --release -p occlude-scenes --example proxy_stats -- city medium`

use occlude_core::inner_box::inner_boxes;
use occlude_scenes::{generate, Size};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let name = args.first().map_or("city", String::as_str);
    let size = match args.get(1).map(String::as_str) {
        Some("small") => Size::Small,
        _ => Size::Medium,
    };
    let scene = generate(name, size, 1).expect("a known scene");
    let mut uses = vec![0u32; scene.meshes.len()];
    for i in &scene.instances {
        uses[i.mesh as usize] += 1;
    }
    let start = Instant::now();
    let (mut with, mut instances_with, mut fraction_sum) = (0, 0u32, 0.0f64);
    for (m, mesh) in scene.meshes.iter().enumerate() {
        let volume = |e: glam::Vec3| f64::from(e.x) * f64::from(e.y) * f64::from(e.z);
        let found = inner_boxes(mesh);
        if !found.is_empty() {
            with += 1;
            instances_with += uses[m];
            let inside: f64 = found.iter().map(|b| volume(b.bounds.extent())).sum();
            fraction_sum += f64::from(uses[m]) * inside / volume(mesh.bounds.extent());
        }
        if args.get(2).is_some() {
            let boxes: Vec<_> = found.iter().map(|b| (b.bounds.min, b.bounds.max)).collect();
            println!("mesh {m}: {} triangles, {} instances, boxes {boxes:?}", mesh.triangle_count(), uses[m]);
        }
    }
    println!(
        "{name}: {} meshes, {with} with a box ({} of {} instances; mean volume fraction {:.2}); {:.1} ms",
        scene.meshes.len(),
        instances_with,
        scene.instances.len(),
        fraction_sum / f64::from(instances_with.max(1)),
        start.elapsed().as_secs_f64() * 1e3
    );
}
