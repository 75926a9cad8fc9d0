//! `occlude calibrate --backend wgpu`: measures, through the wgpu backend, the
//! costs the soft backend's simulated clock charges (`GpuModel`: draw calls,
//! triangles, fragments, state changes, queries, query latency) on the current
//! adapter, and checks how well the soft backend with those costs predicts
//! the measured frame time of each method (`docs/design.md`, "The simulated GPU
//! clock": the model is "calibratable from measurements on the wgpu backend").
//!
//! Each cost comes from a synthetic frame that isolates it (many draws of an
//! off-screen triangle, many zero-coverage triangles, full-screen quads, query
//! boxes; for GPU-driven culling many tiny dispatches, one over a million
//! flags, batched tests of tiny and of screen-covering boxes, a list draw of
//! off-screen triangles, a read-back; queries counted in an item-buffer
//! batch), minus an empty frame's time, as the
//! median of several repeats; an item-buffer batch's GPU cost from a line
//! fitted through frames of the same queries in more and fewer batches. On
//! an adapter without GPU-resident culling the GPU-driven costs stay those
//! of `modern`, and the TOML says so.

use crate::config::BackendKind;
use crate::error::{Error, Result};
use crate::progress::Progress;
use crate::{runner, BenchConfig};
use glam::{Mat4, Vec3};
use occlude_core::{
    Aabb, Backend, Camera, CameraPath, FrameStats, GpuCulling, GpuCullingUnsupported, Keyframe, Mesh, QueryHandle,
    QueryMode, Scene,
};
use occlude_soft::GpuModel;
use occlude_wgpu::{GpuContext, GpuScene, WgpuBackend};
use std::sync::Arc;
use std::time::Instant;

/// What to measure and how to check the result.
#[derive(Clone, Debug)]
pub struct CalibrateConfig {
    /// Image size of the synthetic frames and of the check.
    pub resolution: (u32, u32),
    /// Repeats of each synthetic frame; the median counts.
    pub repeats: usize,
    /// The benchmark that checks the prediction (its backend is ignored:
    /// it runs on wgpu and on soft with the calibrated model). `None` skips
    /// the check.
    pub check: Option<BenchConfig>,
}

/// How well the calibrated model predicts one method.
#[derive(Clone, Debug, PartialEq)]
pub struct Prediction {
    /// Method name.
    pub method: String,
    /// Mean frame time measured on the GPU, ms.
    pub measured_ms: f64,
    /// Mean frame time the soft backend predicts with the calibrated model, ms.
    pub predicted_ms: f64,
}

impl Prediction {
    /// Predicted over measured.
    pub fn ratio(&self) -> f64 {
        self.predicted_ms / self.measured_ms
    }
}

/// A calibration's result.
#[derive(Clone, Debug)]
pub struct Calibration {
    /// The adapter measured.
    pub adapter: String,
    /// The measured costs, named `calibrated`.
    pub model: GpuModel,
    /// Per method, the check of the prediction (empty when skipped).
    pub predictions: Vec<Prediction>,
    /// Why the GPU-driven costs were not measured (kept from `modern`), if
    /// they were not.
    pub culling_unmeasured: Option<String>,
}

impl Calibration {
    /// The model as a TOML file `GpuModel::load` reads, with the adapter and
    /// the check's ratios as comments.
    pub fn to_toml(&self) -> Result<String> {
        let mut text = format!(
            "# GPU model calibrated on the wgpu backend, adapter {}.\n\
             # cpu_node_us is not measured (CPU traversal cost): kept from the `modern` preset.\n",
            self.adapter
        );
        if let Some(why) = &self.culling_unmeasured {
            text += &format!("# GPU-driven culling costs not measured ({why}): kept from the `modern` preset.\n");
        }
        for p in &self.predictions {
            text += &format!(
                "# check {}: measured {:.3} ms, predicted {:.3} ms, ratio {:.2}\n",
                p.method,
                p.measured_ms,
                p.predicted_ms,
                p.ratio()
            );
        }
        text += &toml::to_string(&self.model).map_err(Error::Toml)?;
        Ok(text)
    }
}

/// Instances of the synthetic scene.
const OFF_SCREEN_A: u32 = 0;
const OFF_SCREEN_B: u32 = 1;
const SLIVERS: u32 = 2;
const FIRST_QUAD: u32 = 3;
/// Full-screen quads, drawn back to front so that every fragment passes.
const QUADS: u32 = 24;
/// Triangles of the sliver mesh: each far smaller than a pixel (a strip of
/// them is 2 cm long, one or two pixels at 10 m), so they cost setup and almost
/// no fragments.
const SLIVER_TRIANGLES: u32 = 20_000;
/// Triangles per strip of the sliver mesh.
const SLIVER_STRIP: u32 = 20;
/// Draw calls of the draw and state-change frames.
const DRAWS: usize = 3000;
/// Queries of the small-box frame and of the full-screen frame.
const SMALL_QUERIES: usize = 1000;
const SCREEN_QUERIES: usize = 50;
/// Dispatches of the dispatch frame, flags of the compute-item frame, boxes
/// of the batched tiny-box frame and of the screen-box frame.
const DISPATCHES: usize = 200;
const COMPUTE_ITEMS: u32 = 1 << 20;
const TEST_BOXES: u32 = 10_000;
const SCREEN_TEST_BOXES: u32 = 50;
/// Frames of the latency measurement.
const LATENCY_FRAMES: usize = 30;
/// Item-buffer batches the [`SMALL_QUERIES`] queries of the batch frames
/// are split into, one frame per count; from 10, so that every frame
/// submits batches before its end, as a query method's frames do.
const HIB_BATCHES: [usize; 4] = [10, 25, 50, 100];
/// Most availability checks of a query in flight per latency frame, to time
/// the check.
const LATENCY_CHECKS: u32 = 8;

/// The synthetic scene: two materials on an off-screen triangle, a mesh of
/// slivers, and full-screen quads at increasing distance.
fn synthetic_scene() -> Scene {
    let mut scene = Scene::new("calibration");
    scene.path = CameraPath {
        keyframes: vec![Keyframe { time: 0.0, position: Vec3::ZERO, target: Vec3::NEG_Z, fov_y_deg: 60.0 }],
    };
    let triangle = scene.add_mesh(Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]));
    let off_screen = Mat4::from_translation(Vec3::new(1000.0, 0.0, -10.0));
    scene.add_instance(triangle, off_screen, 0);
    scene.add_instance(triangle, off_screen, 1);
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for strip in 0..SLIVER_TRIANGLES / SLIVER_STRIP {
        // Spread over the view at 10 m: strips of slivers 1 mm wide, far below a
        // pixel, each triangle sharing two vertices with the previous one, as in
        // a scene's meshes (about one vertex to shade per triangle, not three).
        let (x, y) = ((strip % 200) as f32 * 0.05 - 5.0, (strip / 200) as f32 * 0.05 - 2.5);
        let base = positions.len() as u32;
        positions
            .extend((0..SLIVER_STRIP + 2).map(|j| Vec3::new(x + j as f32 * 1e-3, y + (j % 2) as f32 * 1e-3, -10.0)));
        indices.extend((0..SLIVER_STRIP).flat_map(|j| [base + j, base + j + 1, base + j + 2]));
    }
    let slivers = scene.add_mesh(Mesh::new(positions, indices));
    scene.add_instance(slivers, Mat4::IDENTITY, 0);
    let quad = scene.add_mesh(Mesh::new(
        vec![
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ],
        vec![0, 1, 2, 0, 2, 3],
    ));
    for k in 0..QUADS {
        // Back to front: quad k is nearer than quad k - 1, and wide enough
        // to fill a 60-degree view at its distance.
        let z = 40.0 - k as f32;
        scene.add_instance(quad, Mat4::from_translation(Vec3::new(0.0, 0.0, -z)) * Mat4::from_scale(Vec3::splat(z)), 0);
    }
    scene
}

/// The time a frame took beyond `base_ms`, per one of `count` things it did
/// (ms; 0 when noise made it faster than the base).
fn per(total_ms: f64, base_ms: f64, count: f64) -> f64 {
    ((total_ms - base_ms) / count).max(0.0)
}

/// Median of the values.
fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}

/// Runs `body` in `repeats` frames and returns the median CPU and GPU time (ms).
fn timed(backend: &mut WgpuBackend, camera: &Camera, repeats: usize, body: impl Fn(&mut WgpuBackend)) -> (f64, f64) {
    let frames: Vec<FrameStats> = (0..repeats)
        .map(|_| {
            backend.begin_frame(camera);
            body(backend);
            backend.end_frame()
        })
        .collect();
    (median(frames.iter().map(|f| f.cpu_ms).collect()), median(frames.iter().map(|f| f.gpu_ms).collect()))
}

/// Issues `count` queries of `query_box`, their results left unread.
fn issue_queries(backend: &mut WgpuBackend, count: usize, query_box: Aabb) {
    (0..count).for_each(|_| {
        backend.issue_query(&[query_box]);
    });
}

/// Measures the cost model on `ctx`'s adapter, and why its GPU-driven costs
/// could not be measured, if they could not.
pub fn measure_model(ctx: Arc<GpuContext>, config: &CalibrateConfig) -> Result<(GpuModel, Option<String>)> {
    if !ctx.timestamps {
        return Err(Error::Backend(format!(
            "GPU adapter '{}' has no timestamp queries: its GPU costs cannot be measured",
            ctx.adapter_name()
        )));
    }
    let scene = synthetic_scene();
    let (w, h) = config.resolution;
    let gpu = Arc::new(GpuScene::new(Arc::clone(&ctx), &scene)?);
    let mut backend = WgpuBackend::new(gpu, &scene, w, h);
    let camera = Camera {
        position: Vec3::ZERO,
        target: Vec3::NEG_Z,
        up: Vec3::Y,
        fov_y_deg: 60.0,
        aspect: w as f32 / h as f32,
        near: 0.25,
        far: 100.0,
        matrices: None,
    };
    let repeats = config.repeats.max(1);
    let pixels = f64::from(w) * f64::from(h);

    let (cpu0, gpu0) = timed(&mut backend, &camera, repeats, |_| {});
    let (cpu_draws, gpu_draws) = timed(&mut backend, &camera, repeats, |b| {
        (0..DRAWS).for_each(|_| b.draw(&[OFF_SCREEN_A]));
    });
    let (cpu_states, gpu_states) = timed(&mut backend, &camera, repeats, |b| {
        (0..DRAWS).for_each(|k| b.draw(&[if k % 2 == 0 { OFF_SCREEN_A } else { OFF_SCREEN_B }]));
    });
    let sliver_draws = 10;
    let (_, gpu_slivers) = timed(&mut backend, &camera, repeats, |b| {
        (0..sliver_draws).for_each(|_| b.draw(&[SLIVERS]));
    });
    let quad_list: Vec<u32> = (FIRST_QUAD..FIRST_QUAD + QUADS).collect();
    let (_, gpu_quads) = timed(&mut backend, &camera, repeats, |b| b.draw(&quad_list));
    let small_box = Aabb::new(Vec3::new(-0.05, -0.05, -50.0), Vec3::new(0.05, 0.05, -49.9));
    let screen_box = Aabb::new(Vec3::new(-3.0, -3.0, -3.0), Vec3::new(3.0, 3.0, -2.0));
    let (cpu_queries, gpu_queries) =
        timed(&mut backend, &camera, repeats, |b| issue_queries(b, SMALL_QUERIES, small_box));
    let (_, gpu_screen_queries) =
        timed(&mut backend, &camera, repeats, |b| issue_queries(b, SCREEN_QUERIES, screen_box));

    let draw_us = |total: f64, base: f64| per(total, base, DRAWS as f64) * 1e3;
    let gpu_draw_call_us = draw_us(gpu_draws, gpu0);
    let gpu_query_box_us = per(gpu_queries, gpu0, SMALL_QUERIES as f64) * 1e3;
    let (latency_us, poll_us) = measure_latency(&mut backend, &camera, small_box, gpu_query_box_us);
    let mut model = GpuModel {
        name: "calibrated".into(),
        cpu_draw_call_us: draw_us(cpu_draws, cpu0),
        cpu_state_change_us: draw_us(cpu_states, cpu_draws),
        cpu_query_us: per(cpu_queries, cpu0, SMALL_QUERIES as f64) * 1e3,
        cpu_query_poll_us: poll_us,
        cpu_node_us: GpuModel::modern().cpu_node_us,
        gpu_draw_call_us,
        gpu_triangle_ns: per(gpu_slivers - gpu0 - sliver_draws as f64 * gpu_draw_call_us * 1e-3, 0.0, 1.0)
            / (sliver_draws as f64 * f64::from(SLIVER_TRIANGLES))
            * 1e6,
        gpu_fragment_ns: per(gpu_quads - f64::from(QUADS) * gpu_draw_call_us * 1e-3, gpu0, f64::from(QUADS) * pixels)
            * 1e6,
        gpu_state_change_us: draw_us(gpu_states, gpu_draws),
        gpu_query_box_us,
        gpu_query_fragment_ns: per(
            gpu_screen_queries - SCREEN_QUERIES as f64 * gpu_query_box_us * 1e-3,
            gpu0,
            SCREEN_QUERIES as f64 * pixels,
        ) * 1e6,
        query_latency_us: latency_us,
        ..GpuModel::modern()
    };
    let boxes = Boxes { tiny: small_box, screen: screen_box, pixels };
    let unmeasured = measure_culling(&mut backend, &camera, repeats, boxes, &mut model)
        .and_then(|()| measure_hib_query(&mut backend, &camera, repeats, small_box, &mut model))
        .err()
        .map(|e| e.0);
    Ok((model, unmeasured))
}

/// The boxes of the culling frames: one of a few pixels, one covering the
/// screen, both in front of nothing; and the screen's pixel count.
struct Boxes {
    tiny: Aabb,
    screen: Aabb,
    pixels: f64,
}

/// Sets `model`'s GPU-driven culling costs from frames of [`GpuCulling`]
/// commands, each isolating one cost (the empty frame's time and the
/// dispatch around it subtracted), or says why the backend cannot run them.
fn measure_culling(
    backend: &mut WgpuBackend,
    camera: &Camera,
    repeats: usize,
    boxes: Boxes,
    model: &mut GpuModel,
) -> Result<(), GpuCullingUnsupported> {
    let c = backend.gpu_culling()?;
    let one_flag = c.create_flags(1);
    let one_slot = c.create_list(1, &[]);
    let many_flags = c.create_flags(COMPUTE_ITEMS);
    let tiny = c.create_boxes(&vec![boxes.tiny; TEST_BOXES as usize]);
    let screen = c.create_boxes(&vec![boxes.screen; SCREEN_TEST_BOXES as usize]);
    let tiny_ids = c.create_list(TEST_BOXES, &(0..TEST_BOXES).collect::<Vec<_>>());
    let screen_ids = c.create_list(SCREEN_TEST_BOXES, &(0..SCREEN_TEST_BOXES).collect::<Vec<_>>());
    let tested = c.create_flags(TEST_BOXES);
    let draws = c.create_list(DRAWS as u32, &vec![OFF_SCREEN_A; DRAWS]);
    fn culling(b: &mut WgpuBackend) -> &mut dyn GpuCulling {
        b.gpu_culling().expect("checked above")
    }

    let (cpu0, gpu0) = timed(backend, camera, repeats, |_| {});
    let (cpu_dispatches, gpu_dispatches) = timed(backend, camera, repeats, |b| {
        (0..DISPATCHES).for_each(|_| culling(b).compact(one_flag, None, one_slot));
    });
    let dispatch_us = per(gpu_dispatches, gpu0, DISPATCHES as f64) * 1e3;
    // The time of one command of `count` elements, less the empty frame and a
    // dispatch, per element, ms.
    let per_element = |gpu: f64, count: f64| per(gpu - dispatch_us * 1e-3, gpu0, count);
    let (_, gpu_items) = timed(backend, camera, repeats, |b| culling(b).compact(many_flags, None, one_slot));
    let (_, gpu_tiny) = timed(backend, camera, repeats, |b| culling(b).test_boxes(tiny, tiny_ids, tested));
    let (_, gpu_screen) = timed(backend, camera, repeats, |b| culling(b).test_boxes(screen, screen_ids, tested));
    let (_, gpu_list) = timed(backend, camera, repeats, |b| culling(b).draw_list(draws));
    // From recording a dispatch to holding its list's length, µs; the
    // frame's first read-back also clears the target, so it is not timed.
    let waits: Vec<f64> = (0..repeats)
        .map(|_| {
            backend.begin_frame(camera);
            let c = culling(backend);
            c.read_count(one_slot);
            let start = Instant::now();
            c.compact(one_flag, None, one_slot);
            c.read_count(one_slot);
            let us = start.elapsed().as_secs_f64() * 1e6;
            backend.end_frame();
            us
        })
        .collect();

    model.cpu_dispatch_us = per(cpu_dispatches, cpu0, DISPATCHES as f64) * 1e3;
    model.gpu_dispatch_us = dispatch_us;
    model.gpu_compute_item_ns = per_element(gpu_items, f64::from(COMPUTE_ITEMS)) * 1e6;
    model.gpu_box_us = per_element(gpu_tiny, f64::from(TEST_BOXES)) * 1e3;
    let screen_pixels = f64::from(SCREEN_TEST_BOXES) * boxes.pixels;
    let box_pixel_ns =
        per_element(gpu_screen - f64::from(SCREEN_TEST_BOXES) * model.gpu_box_us * 1e-3, screen_pixels) * 1e6;
    model.gpu_box_fragment_ns = (box_pixel_ns - model.gpu_query_fragment_ns).max(0.0);
    model.gpu_indirect_draw_us = per_element(gpu_list, DRAWS as f64) * 1e3;
    model.readback_us = (median(waits) - dispatch_us).max(0.0);
    Ok(())
}

/// Sets `model`'s item-buffer costs (`QueryMode::Hib`): `cpu_hib_query_us`
/// from a frame of [`SMALL_QUERIES`] queries of `small_box` counted in one
/// batch, as `cpu_query_us` from hardware queries (its CPU time beyond an
/// empty frame's, per query, the batch's one submission at the frame's end
/// shared among them); `gpu_hib_batch_us` from [`measure_hib_batch`].
/// Needs the compute shaders of GPU-resident culling.
fn measure_hib_query(
    backend: &mut WgpuBackend,
    camera: &Camera,
    repeats: usize,
    small_box: Aabb,
    model: &mut GpuModel,
) -> Result<(), GpuCullingUnsupported> {
    backend.set_query_mode(QueryMode::Hib)?;
    let (cpu0, _) = timed(backend, camera, repeats, |_| {});
    let (cpu_queries, _) = timed(backend, camera, repeats, |b| issue_queries(b, SMALL_QUERIES, small_box));
    model.cpu_hib_query_us = Some(per(cpu_queries, cpu0, SMALL_QUERIES as f64) * 1e3);
    measure_hib_batch(backend, camera, repeats, small_box, model);
    backend.set_query_mode(QueryMode::Hardware)?;
    Ok(())
}

/// Sets `model`'s `gpu_hib_batch_us`, the backend in `QueryMode::Hib`:
/// the slope of a least-squares line through the median GPU times of
/// frames that split the same [`SMALL_QUERIES`] queries into each of
/// [`HIB_BATCHES`] batches (the counts taking turns, `repeats` frames
/// each), each batch ended as a method ends one, by a check of its last
/// query (which submits it). The CPU's times of such frames give no batch
/// cost of the CPU's own on lavapipe: once a frame submits before its end
/// they hold the GPU's time, the CPU blocked behind the rasterizer's
/// threads (`docs/benchmarks.md`), so a batch keeps `cpu_dispatch_us`.
fn measure_hib_batch(
    backend: &mut WgpuBackend,
    camera: &Camera,
    repeats: usize,
    small_box: Aabb,
    model: &mut GpuModel,
) {
    // The counts take turns frame by frame, so that a burst of other load
    // slows every count's frames alike rather than one count's.
    let mut gpu_ms = vec![Vec::new(); HIB_BATCHES.len()];
    for _ in 0..repeats {
        for (times, &batches) in gpu_ms.iter_mut().zip(&HIB_BATCHES) {
            backend.begin_frame(camera);
            for _ in 0..batches {
                let queries: Vec<QueryHandle> =
                    (0..SMALL_QUERIES / batches).map(|_| backend.issue_query(&[small_box])).collect();
                if let Some(&last) = queries.last() {
                    backend.is_available(last);
                }
            }
            times.push(backend.end_frame().gpu_ms);
        }
    }
    let frames = HIB_BATCHES.iter().zip(gpu_ms).map(|(&batches, times)| (batches as f64, median(times)));
    model.gpu_hib_batch_us = Some((slope(frames) * 1e3).max(0.0));
}

/// Slope of the least-squares line through the points (x, y); 0 for fewer
/// than two distinct x.
fn slope(points: impl Iterator<Item = (f64, f64)> + Clone) -> f64 {
    let n = points.clone().count() as f64;
    let (mx, my) = points.clone().fold((0.0, 0.0), |(sx, sy), (x, y)| (sx + x / n, sy + y / n));
    let (sxy, sxx) = points.fold((0.0, 0.0), |(sxy, sxx), (x, y)| (sxy + (x - mx) * (y - my), sxx + (x - mx).powi(2)));
    if sxx > 0.0 {
        sxy / sxx
    } else {
        0.0
    }
}

/// Time from a query's submission until its result is read, waiting for it as
/// stop-and-wait does (blocking, not spinning: on a CPU "GPU" such as
/// lavapipe a spinning check takes a core from the rasterizer's threads and
/// measured latencies six times too long), minus the GPU time of its box (the
/// model's latency, which so includes the cost of a submission and its render
/// pass); and the CPU time of one availability check of a query in flight, from
/// at most [`LATENCY_CHECKS`] checks before the wait. Medians over several
/// frames, in µs.
fn measure_latency(backend: &mut WgpuBackend, camera: &Camera, small_box: Aabb, box_us: f64) -> (f64, f64) {
    let mut latencies = Vec::new();
    let mut polls = Vec::new();
    for _ in 0..LATENCY_FRAMES {
        backend.begin_frame(camera);
        // The frame's first pass clears the target: keep it out of the timing.
        let clearing = backend.issue_query(&[small_box]);
        backend.result(clearing);
        let query = backend.issue_query(&[small_box]);
        // The first check submits the query (and may already find it done).
        let start = Instant::now();
        let mut available = backend.is_available(query);
        let submitted = Instant::now();
        let mut checks = 0u32;
        while !available && checks < LATENCY_CHECKS {
            available = backend.is_available(query);
            checks += 1;
        }
        let polling_us = submitted.elapsed().as_secs_f64() * 1e6;
        backend.result(query);
        let until_read = start.elapsed().as_secs_f64() * 1e6;
        backend.end_frame();
        latencies.push((until_read - box_us).max(0.0));
        if checks > 0 {
            polls.push(polling_us / f64::from(checks));
        }
    }
    (median(latencies), median(polls))
}

/// Measures the model and, if asked, checks its predictions.
pub fn calibrate(config: &CalibrateConfig, progress: &dyn Progress) -> Result<Calibration> {
    crate::limits::check_resolution(config.resolution).map_err(Error::Invalid)?;
    crate::limits::check_repeats(config.repeats).map_err(|e| Error::Invalid(format!("--repeats: {e}")))?;
    let ctx = Arc::new(GpuContext::new()?);
    let adapter = ctx.adapter_name();
    progress.message(&format!("measuring {adapter}"));
    let (model, culling_unmeasured) = measure_model(ctx, config)?;
    model.validate().map_err(|e| Error::Backend(format!("the model measured on {adapter} is not usable: {e}")))?;
    let gpu_costs = [model.gpu_draw_call_us, model.gpu_triangle_ns, model.gpu_fragment_ns, model.gpu_query_box_us];
    if !gpu_costs.iter().any(|&c| c > 0.0) {
        return Err(Error::Backend(format!(
            "{adapter} measured no GPU time for draws, triangles, fragments or query boxes: the measurement \
             failed, no model is written"
        )));
    }
    let predictions = match &config.check {
        Some(check) => predict(check, &model, progress)?,
        None => Vec::new(),
    };
    Ok(Calibration { adapter, model, predictions, culling_unmeasured })
}

/// Runs `check` on the GPU and on the soft backend with `model`, and pairs
/// the mean frame times per method.
pub fn predict(check: &BenchConfig, model: &GpuModel, progress: &dyn Progress) -> Result<Vec<Prediction>> {
    let measured = BenchConfig { backend: BackendKind::Wgpu, ..check.clone() };
    let predicted = BenchConfig { backend: BackendKind::Soft, gpu_model: model.clone(), ..check.clone() };
    progress.message(&format!("checking on {} (wgpu)", check.scene));
    let on_gpu = runner::run(&measured, progress)?.report(&measured);
    progress.message(&format!("checking on {} (soft, calibrated)", check.scene));
    let on_soft = runner::run(&predicted, progress)?.report(&predicted);
    Ok(on_gpu
        .methods
        .iter()
        .zip(&on_soft.methods)
        .map(|(g, s)| Prediction {
            method: g.name.clone(),
            measured_ms: g.mean_frame_ms,
            predicted_ms: s.mean_frame_ms,
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fit recovers a line's slope, and gives 0 where no slope exists.
    #[test]
    fn slope_fits_a_line() {
        let line = [1.0, 10.0, 50.0, 100.0].map(|x| (x, 0.25 * x + 3.0));
        assert!((slope(line.into_iter()) - 0.25).abs() < 1e-12);
        let noisy = [(1.0, 1.0), (2.0, 3.0), (3.0, 2.0)];
        assert!((slope(noisy.into_iter()) - 0.5).abs() < 1e-12);
        assert_eq!(slope([(2.0, 1.0), (2.0, 5.0)].into_iter()), 0.0);
        assert_eq!(slope(std::iter::empty()), 0.0);
    }
}
