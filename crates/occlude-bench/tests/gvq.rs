//! Granular visibility queries with summed area tables
//! on the soft backend, on frames of the `small` scenes' walkthroughs:
//! the counts keep the paper's guarantees against the exact counts, and
//! the exact counts are the oracle's; and on the wgpu backend (lavapipe
//! with `OCCLUDE_REQUIRE_GPU=1`) the same plans count the same.

use occlude_bench::config::NEAR_PLANE;
use occlude_bench::runner::far_plane;
use occlude_core::gvq::{RegionMode, SatConfig, SummedAreaTable};
use occlude_core::{Camera, Instruments, Sampling, Scene};
use occlude_scenes::{generate, Size};
use occlude_soft::sat::SoftSat;
use occlude_soft::{GpuModel, SoftBackend};
use occlude_wgpu::{GpuContext, GpuSat};

const RESOLUTION: (u32, u32) = (128, 96);

/// The scenes checked, each with `frames` cameras spread over its walkthrough.
fn scenes(frames: usize) -> Vec<(Scene, Vec<Camera>)> {
    ["teapots", "city", "plant", "figures", "rooms"]
        .into_iter()
        .map(|name| {
            let scene = generate(name, Size::Small, 1).unwrap();
            let aspect = RESOLUTION.0 as f32 / RESOLUTION.1 as f32;
            let cameras = scene.path.sample_with(Sampling::Spread(frames), aspect, NEAR_PLANE, far_plane(&scene));
            (scene, cameras)
        })
        .collect()
}

#[test]
fn sat_counts_keep_the_region_sets_guarantees() {
    let configs: Vec<SatConfig> = [1, 2]
        .into_iter()
        .flat_map(|targets| {
            [RegionMode::Conservative, RegionMode::Approximate].map(|mode| SatConfig {
                targets,
                mode,
                ..SatConfig::default()
            })
        })
        .collect();
    let mut exact_checked = 0;
    let mut conflict_frames = 0;
    for (scene, cameras) in scenes(6) {
        let mut sat = SoftSat::new(RESOLUTION.0, RESOLUTION.1);
        for (f, camera) in cameras.iter().enumerate() {
            for (config, frame) in configs.iter().zip(sat.query(&scene, camera, &configs)) {
                let SatConfig { targets, mode, .. } = *config;
                conflict_frames += usize::from(frame.plan.conflicts > 0);
                for i in 0..frame.plan.sets.len() {
                    let (count, exact) = (frame.counts[i], frame.exact[i]);
                    let at = format!("{} frame {f}, {targets} targets, {mode:?}, object {i}", scene.name);
                    match mode {
                        RegionMode::Conservative => assert!(count >= exact, "{at}: {count} < {exact}"),
                        RegionMode::Approximate => assert!(count <= exact, "{at}: {count} > {exact}"),
                    }
                    if frame.plan.counted_exactly(i) {
                        assert_eq!(count, exact, "{at}: nothing shared, left out or shared over it");
                        exact_checked += usize::from(exact > 0);
                    }
                }
                if frame.plan.conflicts == 0 {
                    assert_eq!(frame.errors.wrong, 0, "{} frame {f}: no conflict, every count exact", scene.name);
                }
            }
        }
    }
    assert!(exact_checked > 100, "only {exact_checked} visible objects were checked exact");
    assert!(conflict_frames > 0, "no frame had a conflict object: the split was not exercised");
}

#[test]
fn exact_counts_are_the_oracles_pixel_counts() {
    for (scene, cameras) in scenes(4) {
        let mut sat = SoftSat::new(RESOLUTION.0, RESOLUTION.1);
        let mut backend = SoftBackend::new(&scene, RESOLUTION.0, RESOLUTION.1, GpuModel::modern());
        let all: Vec<u32> = (0..scene.instances.len() as u32).collect();
        for (f, camera) in cameras.iter().enumerate() {
            let frame = sat.query(&scene, camera, &[SatConfig::default()]).remove(0);
            let oracle = backend.oracle(camera, &all);
            // The oracle counts a pixel for every object at its depth; the
            // owner is the first of them drawn.
            for (i, (&owned, &seen)) in frame.exact.iter().zip(&oracle.pixels).enumerate() {
                assert!(owned <= seen, "{} frame {f}, object {i}: owns {owned} of {seen} pixels", scene.name);
                assert_eq!(owned > 0, seen > 0, "{} frame {f}, object {i}: owns {owned} of {seen} pixels", scene.name);
            }
            let covered = oracle.depth.iter().filter(|&&d| d < 1.0).count() as u64;
            assert_eq!(frame.exact.iter().sum::<u64>(), covered, "{} frame {f}: every covered pixel owned", scene.name);
            let ties: u64 = oracle.pixels.iter().sum::<u64>() - covered;
            assert!(ties * 50 <= covered, "{} frame {f}: {ties} tied pixels of {covered}", scene.name);
        }
    }
}

/// The wgpu backend's counts of the soft backend's plans: its prefix sums
/// and lookups are exact on its own image (they equal the CPU's summed
/// area table of the image read back), and they equal soft's counts except
/// where the two rasterizers round vertex positions differently, by at
/// most `ROUNDING_PIXELS` per object (as `tests/gpu.rs` allows the
/// oracles); the differences are printed.
#[test]
fn wgpu_counts_equal_the_soft_backends_on_the_same_frames() {
    const ROUNDING_PIXELS: u64 = 8;
    let Some(ctx) = GpuContext::for_test("wgpu_counts_equal_the_soft_backends_on_the_same_frames") else { return };
    let (w, h) = RESOLUTION;
    let (mut compared, mut differing, mut worst) = (0, 0, (0u64, String::new()));
    for (scene, cameras) in scenes(3) {
        let mut soft = SoftSat::new(w, h);
        for targets in [1, 2] {
            let gpu = GpuSat::new(ctx.clone(), w, h, targets);
            for (f, camera) in cameras.iter().enumerate() {
                let config = SatConfig { targets, ..SatConfig::default() };
                let frame = soft.query(&scene, camera, &[config]).remove(0);
                let counted = gpu.query(&scene, camera, &frame.plan).unwrap();
                let at = format!("{} frame {f}, {targets} targets", scene.name);
                let sat = SummedAreaTable::from_channel_image(w, h, frame.plan.channels, &counted.channel_image);
                let on_cpu: Vec<u64> = frame.plan.sets.iter().map(|s| sat.count_set(s)).collect();
                assert_eq!(counted.counts, on_cpu, "{at}: GPU sums against the CPU's on the GPU's image");
                for (i, (&g, &s)) in counted.counts.iter().zip(&frame.counts).enumerate() {
                    let d = g.abs_diff(s);
                    let what = format!("{at}, object {i}: wgpu {g}, soft {s}");
                    assert!(d <= ROUNDING_PIXELS, "{what}");
                    compared += usize::from(s > 0);
                    differing += usize::from(d > 0);
                    if d > worst.0 {
                        worst = (d, what);
                    }
                }
            }
        }
    }
    assert!(compared > 100, "only {compared} visible objects compared");
    eprintln!("wgpu against soft: {differing} of {compared} visible objects' counts differ; worst: {}", worst.1);
}
