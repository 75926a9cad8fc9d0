//! Per-method averages over a walkthrough, in the JSON schema of `docs/design.md`.

use crate::config::{BackendKind, BenchConfig};
use crate::runner::{BenchRun, MethodRun};
use occlude_core::{FrameStats, Hierarchy, Scene};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Figures about the scene and hierarchy a run used.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SceneStats {
    /// Triangles over all instances.
    pub triangles: u64,
    /// Triangles stored once per mesh.
    pub unique_triangles: u64,
    /// Instances (objects).
    pub instances: u64,
    /// Distinct materials.
    pub materials: u32,
    /// Hierarchy nodes.
    pub nodes: u64,
    /// Hierarchy leaves.
    pub leaves: u64,
    /// Deepest hierarchy level.
    pub depth: u32,
    /// Frames in the walkthrough.
    pub frames: usize,
    /// Real time the hierarchy build took (varies between runs).
    pub build_wall_ms: f64,
}

impl SceneStats {
    /// Figures of `scene` under `hierarchy` over `frames` frames.
    pub fn new(scene: &Scene, hierarchy: &Hierarchy, frames: usize) -> Self {
        Self {
            triangles: scene.triangle_count() as u64,
            unique_triangles: scene.unique_triangle_count() as u64,
            instances: scene.instances.len() as u64,
            materials: scene.material_count,
            nodes: hierarchy.node_count() as u64,
            leaves: hierarchy.leaf_count() as u64,
            depth: hierarchy.max_depth(),
            frames,
            build_wall_ms: hierarchy.build_time.as_secs_f64() * 1e3,
        }
    }
}

/// One method's averages (per frame) over the walkthrough.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MethodSummary {
    /// Method name (`vfc`, `sw`, `opt`, ...).
    pub name: String,
    /// Parameter values in use, defaults included.
    pub params: BTreeMap<String, String>,
    /// Mean frame time (simulated on the soft backend), ms.
    pub mean_frame_ms: f64,
    /// 95th-percentile frame time, ms.
    pub p95_frame_ms: f64,
    /// Occlusion queries per frame.
    pub queries_per_frame: f64,
    /// CPU time blocked on query results per frame, ms.
    pub wait_ms_per_frame: f64,
    /// CPU time blocked in submitting calls per frame (a full driver
    /// queue; see `FrameStats::submit_wait_ms`), ms.
    #[serde(default)]
    pub submit_wait_ms_per_frame: f64,
    /// Draw calls per frame.
    pub draw_calls_per_frame: f64,
    /// State changes per frame: switches between drawing and querying, as
    /// the CHC++ paper counts them (`FrameStats::state_changes`).
    pub state_changes_per_frame: f64,
    /// Material switches per frame: switches between drawing states with
    /// no query between them (`FrameStats::material_switches`).
    #[serde(default)]
    pub material_switches_per_frame: f64,
    /// Triangles drawn per frame.
    pub triangles_per_frame: f64,
    /// Objects drawn per frame.
    pub visible_objects_per_frame: f64,
    /// Pixels differing from view-frustum culling, summed over all frames.
    pub missing_pixels: u64,
    /// Mean `vfc` frame time over this method's.
    pub speedup_vs_vfc: f64,
    /// Speedup over `vfc` as the papers average it: the mean over frames of
    /// `vfc`'s frame time over this method's.
    #[serde(default)]
    pub mean_speedup_vs_vfc: f64,
    /// This method's mean frame time over `opt`'s (`null` when `opt` was not run).
    pub ratio_to_opt: Option<f64>,
    /// Mean CPU busy time per frame (waits excluded), ms.
    pub cpu_ms_per_frame: f64,
    /// Mean GPU busy time per frame, ms.
    pub gpu_ms_per_frame: f64,
    /// Real time per frame on this machine (rasterizing included; varies).
    pub wall_ms: f64,
    /// GPU time per frame of the occlusion tests (queries, box tests and
    /// their compute passes), ms; see `FrameStats::cull_ms`.
    #[serde(default)]
    pub cull_ms_per_frame: f64,
    /// GPU time per frame of drawing the scene, ms.
    #[serde(default)]
    pub render_ms_per_frame: f64,
    /// GPU time per frame of building depth pyramids, ms; see
    /// `FrameStats::pyramid_ms`.
    #[serde(default)]
    pub pyramid_ms_per_frame: f64,
    /// GPU time per frame after the first pyramid build (`hiz`'s late
    /// pass), ms; see `FrameStats::late_ms`.
    #[serde(default)]
    pub late_ms_per_frame: f64,
    /// Compute dispatches per frame.
    #[serde(default)]
    pub dispatches_per_frame: f64,
    /// Indirect multi-draws per frame (the draws inside them are in
    /// `draw_calls_per_frame` and `indirect_draw_calls_per_frame`).
    #[serde(default)]
    pub indirect_draws_per_frame: f64,
    /// Draws inside indirect multi-draws per frame.
    #[serde(default)]
    pub indirect_draw_calls_per_frame: f64,
    /// GPU-to-CPU read-backs per frame (besides query results).
    #[serde(default)]
    pub readbacks_per_frame: f64,
    /// Real time per frame keeping a moving scene up to date (the
    /// hierarchy's refit or rebuild and the backend's update), ms; 0 in a
    /// still scene. See `FrameStats::update_ms`.
    #[serde(default)]
    pub update_ms_per_frame: f64,
    /// The upkeep per frame as the frame times include it (modelled on
    /// the soft backend, measured on wgpu), ms; see
    /// `FrameStats::update_charged_ms`.
    #[serde(default)]
    pub update_charged_ms_per_frame: f64,
    /// Instances that moved, hid or showed per frame.
    #[serde(default)]
    pub instances_moved_per_frame: f64,
    /// Frames before which the hierarchy was rebuilt.
    #[serde(default)]
    pub rebuilds: u64,
    /// Means per frame of the method's own counters (e.g. `om`'s stage-1
    /// nodes decided without a query and its stage-2 rounds).
    pub counters_per_frame: BTreeMap<String, f64>,
    /// Every frame's statistics.
    pub per_frame: Vec<FrameStats>,
}

/// The whole run: the JSON document `occlude bench --json` writes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BenchReport {
    /// Scene name.
    pub scene: String,
    /// Scene size.
    pub size: String,
    /// Frames in the walkthrough.
    pub frames: usize,
    /// The frame rate the walkthrough was sampled at (`null`: its frames
    /// were spread evenly over it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fps: Option<f32>,
    /// Image width and height.
    pub resolution: [u32; 2],
    /// `soft` (simulated clock) or `wgpu`.
    pub backend: String,
    /// How occlusion queries were counted: `hardware` or `hib` (reports
    /// that predate the choice were `hardware`).
    #[serde(default = "hardware_queries")]
    pub queries: String,
    /// The GPU adapter of a `wgpu` run (name, driver, graphics API).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub adapter: Option<String>,
    /// Why the run stopped early (a lost GPU device); the frames reported
    /// are those every method finished.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub aborted: Option<String>,
    /// Name of the simulated GPU's cost model (`measured` on wgpu).
    pub gpu_model: String,
    /// Hierarchy builder (`bvh` or `kdtree`).
    pub hierarchy: String,
    /// Generator seed.
    pub seed: u64,
    /// Scene and hierarchy figures.
    pub scene_stats: SceneStats,
    /// One entry per method, in the order asked for.
    pub methods: Vec<MethodSummary>,
}

fn hardware_queries() -> String {
    occlude_core::QueryMode::Hardware.to_string()
}

fn mean(frames: &[FrameStats], f: impl Fn(&FrameStats) -> f64) -> f64 {
    if frames.is_empty() {
        return 0.0;
    }
    frames.iter().map(f).sum::<f64>() / frames.len() as f64
}

/// The mean over frames of `reference`'s frame time over `frames`' (frames
/// of no time left out).
fn mean_ratio(reference: &[FrameStats], frames: &[FrameStats]) -> f64 {
    let ratios: Vec<f64> =
        reference.iter().zip(frames).filter(|(_, f)| f.frame_ms > 0.0).map(|(r, f)| r.frame_ms / f.frame_ms).collect();
    ratios.iter().sum::<f64>() / ratios.len().max(1) as f64
}

/// The 95th percentile (nearest rank) of the frame times.
fn p95(frames: &[FrameStats]) -> f64 {
    let mut t: Vec<f64> = frames.iter().map(|f| f.frame_ms).collect();
    t.sort_by(f64::total_cmp);
    let rank = ((t.len() as f64 * 0.95).ceil() as usize).clamp(1, t.len().max(1));
    t.get(rank - 1).copied().unwrap_or(0.0)
}

impl BenchReport {
    /// Summarises a run.
    pub fn new(run: &BenchRun, config: &BenchConfig) -> Self {
        Self::with_methods(run, &run.methods, config)
    }

    /// Summarises `methods`, lanes of `run` (its methods or its variants),
    /// against the run's `vfc` reference, as if they were its only methods.
    pub fn with_methods(run: &BenchRun, methods: &[MethodRun], config: &BenchConfig) -> Self {
        let vfc_ms = mean(&run.reference, |f| f.frame_ms);
        let opt_ms = methods.iter().find(|m| m.name == "opt").map(|m| mean(&m.frames, |f| f.frame_ms));
        let methods = methods
            .iter()
            .map(|m| {
                let frames = &m.frames;
                let frame_ms = mean(frames, |f| f.frame_ms);
                MethodSummary {
                    name: m.name.clone(),
                    params: m.params.iter().cloned().collect(),
                    mean_frame_ms: frame_ms,
                    p95_frame_ms: p95(frames),
                    queries_per_frame: mean(frames, |f| f.queries as f64),
                    wait_ms_per_frame: mean(frames, |f| f.wait_ms),
                    submit_wait_ms_per_frame: mean(frames, |f| f.submit_wait_ms),
                    draw_calls_per_frame: mean(frames, |f| f.draw_calls as f64),
                    state_changes_per_frame: mean(frames, |f| f.state_changes as f64),
                    material_switches_per_frame: mean(frames, |f| f.material_switches as f64),
                    triangles_per_frame: mean(frames, |f| f.triangles as f64),
                    visible_objects_per_frame: mean(frames, |f| f.visible_objects as f64),
                    missing_pixels: frames.iter().map(|f| f.missing_pixels).sum(),
                    speedup_vs_vfc: if frame_ms > 0.0 { vfc_ms / frame_ms } else { 0.0 },
                    mean_speedup_vs_vfc: mean_ratio(&run.reference, frames),
                    ratio_to_opt: opt_ms.filter(|&o| o > 0.0).map(|o| frame_ms / o),
                    cpu_ms_per_frame: mean(frames, |f| f.cpu_ms),
                    gpu_ms_per_frame: mean(frames, |f| f.gpu_ms),
                    wall_ms: mean(frames, |f| f.wall_ms),
                    cull_ms_per_frame: mean(frames, |f| f.cull_ms),
                    render_ms_per_frame: mean(frames, |f| f.render_ms),
                    pyramid_ms_per_frame: mean(frames, |f| f.pyramid_ms),
                    late_ms_per_frame: mean(frames, |f| f.late_ms),
                    dispatches_per_frame: mean(frames, |f| f.dispatches as f64),
                    indirect_draws_per_frame: mean(frames, |f| f.indirect_draws as f64),
                    indirect_draw_calls_per_frame: mean(frames, |f| f.indirect_draw_calls as f64),
                    readbacks_per_frame: mean(frames, |f| f.readbacks as f64),
                    update_ms_per_frame: mean(frames, |f| f.update_ms),
                    update_charged_ms_per_frame: mean(frames, |f| f.update_charged_ms),
                    instances_moved_per_frame: mean(frames, |f| f.instances_moved as f64),
                    rebuilds: frames.iter().map(|f| f.rebuilds).sum(),
                    counters_per_frame: m
                        .counters
                        .iter()
                        .map(|(k, v)| (k.clone(), v.iter().sum::<f64>() / v.len().max(1) as f64))
                        .collect(),
                    per_frame: frames.clone(),
                }
            })
            .collect();
        Self {
            scene: config.scene.clone(),
            size: config.size.to_string(),
            frames: run.scene.frames,
            fps: config.fps,
            resolution: [config.resolution.0, config.resolution.1],
            backend: config.backend.to_string(),
            queries: config.queries.to_string(),
            adapter: run.adapter.clone(),
            aborted: run.aborted.clone(),
            gpu_model: match config.backend {
                BackendKind::Soft => config.gpu_model.name.clone(),
                BackendKind::Wgpu => "measured".into(),
            },
            hierarchy: config.hierarchy.to_string(),
            seed: config.seed,
            scene_stats: run.scene.clone(),
            methods,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_mean_of_ratios_is_not_the_ratio_of_means() {
        let times =
            |t: &[f64]| t.iter().map(|&frame_ms| FrameStats { frame_ms, ..Default::default() }).collect::<Vec<_>>();
        let (vfc, method) = (times(&[10.0, 10.0]), times(&[1.0, 10.0]));
        // Ratios 10 and 1: their mean is 5.5, the ratio of the means 20 / 11.
        assert_eq!(mean_ratio(&vfc, &method), 5.5);
        assert_eq!(mean_ratio(&vfc, &times(&[0.0, 5.0])), 2.0);
        assert_eq!(mean_ratio(&[], &[]), 0.0);
    }

    #[test]
    fn p95_is_nearest_rank() {
        let frames: Vec<FrameStats> =
            (1..=100).map(|i| FrameStats { frame_ms: i as f64, ..Default::default() }).collect();
        assert_eq!(p95(&frames), 95.0);
        assert_eq!(p95(&frames[..1]), 1.0);
        assert_eq!(p95(&[]), 0.0);
    }
}
