//! glTF import speed in triangles per second, on a generated GLB file of
//! about a million triangles in a thousand distinct meshes, one node each
//! (written by `export::glb` to a temporary file, then imported from it).

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::{Mat4, Vec3};
use occlude_core::rng::Rng;
use occlude_core::Scene;
use occlude_scenes::import::{import, ModelFormat};
use occlude_scenes::shapes::{sphere, MeshBuilder};
use occlude_scenes::{export, AutoPath, ImportOptions};
use std::time::Duration;

/// Meshes of the model, each its own sphere of 1024 triangles.
const MESHES: u32 = 1000;

/// A field of [`MESHES`] spheres of random radius and place, each baked into
/// its own mesh so that every triangle is read from the file.
fn million_triangles() -> Scene {
    let mut scene = Scene::new("million");
    scene.material_count = 8;
    let mut rng = Rng::new(1, 0);
    for k in 0..MESHES {
        let at = rng.point_in(Vec3::ZERO, Vec3::new(400.0, 20.0, 400.0));
        let mut ball = MeshBuilder::new();
        ball.add_at(&sphere(rng.range(0.5, 3.0), 17, 32), at);
        let mesh = scene.add_mesh(ball.build());
        scene.add_instance(mesh, Mat4::IDENTITY, k % 8);
    }
    scene
}

fn import_speed(c: &mut Criterion) {
    let scene = million_triangles();
    let dir = tempfile::tempdir().expect("a temporary directory");
    let path = dir.path().join("million.glb");
    std::fs::write(&path, export::glb(&scene)).expect("the model is written");
    let options = ImportOptions { auto_path: AutoPath::Orbit, ..ImportOptions::default() };
    let mut group = c.benchmark_group("import");
    group.sample_size(10).measurement_time(Duration::from_secs(10));
    group.throughput(Throughput::Elements(scene.triangle_count() as u64));
    group.bench_function(format!("glb_{}_triangles", scene.triangle_count()), |b| {
        b.iter(|| import(&path, ModelFormat::Glb, &options).expect("the model imports"))
    });
    group.finish();
}

criterion_group!(benches, import_speed);
criterion_main!(benches);
