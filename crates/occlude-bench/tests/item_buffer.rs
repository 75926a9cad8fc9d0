//! The hierarchical item buffer (Engelhardt and Dachsbacher 2009, section
//! 3.2) on both backends: every frame of every `small` scene's walkthrough,
//! the instances in view counted into `2^2 x 2^2` screen tiles, each
//! object's instances in one instanced draw on the GPU. The counts are
//! compared with exact counts found another way: the rasterizer's depth
//! image and its depth-equal occlusion queries (the oracle pass), and on the
//! soft backend every pixel's owner found fragment by fragment.

use occlude_bench::config::BackendKind;
use occlude_bench::runner::cameras;
use occlude_bench::BenchConfig;
use occlude_core::{Backend, Camera, Instruments, ItemCounts, ItemLayout, OracleView, Scene};
use occlude_scenes::{generate, Size, PAPER_SCENES};
use occlude_soft::raster::Fragments;
use occlude_soft::SoftBackend;
use occlude_wgpu::{GpuContext, GpuScene, WgpuBackend};
use std::sync::Arc;

/// `2^LEVEL x 2^LEVEL` screen tiles.
const LEVEL: u32 = 2;

fn config(scene: &str, backend: BackendKind) -> BenchConfig {
    BenchConfig { scene: scene.into(), frames: 90, resolution: (320, 240), backend, ..BenchConfig::default() }
}

fn in_view(scene: &Scene, camera: &Camera) -> Vec<u32> {
    let frustum = camera.frustum();
    (0..scene.instances.len() as u32).filter(|&i| frustum.intersects(&scene.instances[i as usize].bounds)).collect()
}

/// Covered pixels (depth below the far plane) of `view`'s image per tile.
fn covered_per_tile(layout: &ItemLayout, view: &OracleView) -> Vec<u64> {
    let mut tiles = vec![0u64; layout.tiles() as usize];
    for (p, &d) in view.depth.iter().enumerate() {
        if d < 1.0 {
            let (x, y) = (p as u32 % view.width, p as u32 / view.width);
            tiles[layout.tile_of(x, y, view.width, view.height) as usize] += 1;
        }
    }
    tiles
}

/// The histogram of `layout` in the image `view` by definition: each pixel
/// belongs to the first slot with a fragment at the image's depth there.
fn exact_bins(scene: &Scene, camera: &Camera, layout: &ItemLayout, view: &OracleView) -> Vec<u32> {
    let (w, h) = (view.width, view.height);
    let mut claimed = vec![false; view.depth.len()];
    let mut bins = vec![0u32; layout.bins()];
    let mut fragments = Fragments::new(w, h);
    let view_projection = camera.view_projection();
    for (slot, &i) in layout.slots().iter().enumerate() {
        let instance = &scene.instances[i as usize];
        let mesh = &scene.meshes[instance.mesh as usize];
        let mvp = view_projection * instance.transform;
        let clip: Vec<_> = mesh.positions.iter().map(|p| mvp * p.extend(1.0)).collect();
        for t in mesh.indices.chunks_exact(3) {
            let tri = [clip[t[0] as usize], clip[t[1] as usize], clip[t[2] as usize]];
            fragments.each(&tri, false, |x, y, z| {
                let p = (y * w + x) as usize;
                if z == view.depth[p] && !std::mem::replace(&mut claimed[p], true) {
                    bins[layout.id(slot as u32, layout.tile_of(x, y, w, h)) as usize] += 1;
                }
            });
        }
    }
    bins
}

/// What holds on both backends: the totals are the histogram's sums, every
/// tile counts the covered pixels of the oracle's image, and every instance
/// its depth-equal query's count less at most the frame's excess
/// fragments (fragments at the image's depth beyond one a pixel: the query
/// counts fragments, so one instance's coincident faces count a pixel
/// twice, and so do two instances tied there, which the item buffer gives
/// to the first), exactly that count on a frame without them. Returns
/// whether the frame had excess fragments.
fn check_totals(what: &str, layout: &ItemLayout, counts: &ItemCounts, oracle: &OracleView) -> bool {
    assert_eq!(counts, &ItemCounts::reduce(layout, counts.bins.clone()), "{what}: totals are not the bins' sums");
    let covered = covered_per_tile(layout, oracle);
    assert_eq!(counts.tiles, covered, "{what}: per-tile counts");
    let excess = oracle.pixels.iter().sum::<u64>() - covered.iter().sum::<u64>();
    for (s, (&hib, &query)) in counts.instances.iter().zip(&oracle.pixels).enumerate() {
        assert!(hib <= query && query - hib <= excess, "{what}: slot {s} counted {hib} pixels, its query {query}");
    }
    excess > 0
}

#[test]
fn soft_item_buffer_counts_every_instance_and_tile_exactly() {
    for name in PAPER_SCENES {
        let scene = generate(name, Size::Small, 1).unwrap();
        let cfg = config(name, BackendKind::Soft);
        let (w, h) = cfg.resolution;
        let mut soft = SoftBackend::new(&scene, w, h, cfg.gpu_model.clone());
        let (mut depth, mut tied, mut instanced) = (Vec::new(), 0, false);
        for (f, camera) in cameras(&scene, &cfg).unwrap().iter().enumerate() {
            let what = format!("soft {name} frame {f}");
            let layout = ItemLayout::new(&scene, &in_view(&scene, camera), LEVEL).unwrap();
            instanced |= (0..layout.objects()).any(|o| layout.object_slots(o).len() > 1);
            let counts = soft.item_buffer(camera, &layout);
            soft.depth_image(&mut depth);
            let oracle = soft.oracle(camera, layout.slots());
            let bits = |d: &[f32]| d.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            assert!(bits(&depth) == bits(&oracle.depth), "{what}: the item pass's depth differs from the rasterizer's");
            assert_eq!(counts.bins, exact_bins(&scene, camera, &layout, &oracle), "{what}: histogram");
            tied += usize::from(check_totals(&what, &layout, &counts, &oracle));
        }
        assert!(instanced, "{name}: no object had two instances in view");
        eprintln!("soft {name}: {tied} of {} frames with a pixel covered twice at its depth", cfg.frames);
    }
}

#[test]
fn gpu_item_buffer_counts_every_instance_and_tile_exactly() {
    let Some(ctx) = GpuContext::for_test("gpu_item_buffer_counts_every_instance_and_tile_exactly") else { return };
    for name in PAPER_SCENES {
        let scene = generate(name, Size::Small, 1).unwrap();
        let cfg = config(name, BackendKind::Wgpu);
        let (w, h) = cfg.resolution;
        let gpu = Arc::new(GpuScene::new(Arc::clone(&ctx), &scene).unwrap());
        let mut backend = WgpuBackend::new(gpu, &scene, w, h);
        let (mut depth, mut tied) = (Vec::new(), 0);
        for (f, camera) in cameras(&scene, &cfg).unwrap().iter().enumerate() {
            let what = format!("wgpu {name} frame {f}");
            let layout = ItemLayout::new(&scene, &in_view(&scene, camera), LEVEL).unwrap();
            let counts = backend.item_buffer(camera, &layout).expect("lavapipe runs compute");
            backend.depth_image(&mut depth);
            let oracle = backend.oracle(camera, layout.slots());
            assert_eq!(backend.failure(), None, "{what}");
            let bits = |d: &[f32]| d.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            assert!(bits(&depth) == bits(&oracle.depth), "{what}: the item pass's depth differs from the draws'");
            tied += usize::from(check_totals(&what, &layout, &counts, &oracle));
        }
        eprintln!("wgpu {name}: {tied} of {} frames with a pixel covered twice at its depth", cfg.frames);
    }
}
