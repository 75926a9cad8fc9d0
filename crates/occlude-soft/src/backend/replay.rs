//! Draws counted once for two backends: [`DrawReplay`] carries the draws'
//! counts and the final depth image of one soft backend's frame
//! ([`SoftBackend::record_draws`]) to another that makes the same draws in
//! the same frame ([`SoftBackend::replay_draws`]) and so need not
//! rasterize them: the bench runner's `ideal`, which replays `sw`'s draw
//! calls without its queries.
//!
//! **Why the replaying backend's figures are its own.** It makes the same
//! draw commands, one an instance, in the same order, from the same camera.
//! A draw's cost on the time line is its fixed part plus its `fragments`,
//! the pixels its triangles cover before the depth test: a function of the
//! instance and the camera alone. Its `passed` count (fragments that wrote
//! depth) depends on the depth buffer before it, which holds the same
//! draws' fragments in both backends, because queries write no depth. The
//! final image is the per-pixel minimum of the drawn fragments, so it is
//! the recording backend's. Everything else (the CPU clock, state changes,
//! the flushes) is computed by the replaying backend as usual. The test
//! `a_replayed_frame_has_the_figures_and_image_of_a_rasterized_one` checks
//! it bit for bit, and the bench runner's tests do so on whole walkthroughs.
//!
//! A replaying backend rasterizes no draw, so its depth buffer is empty
//! during the frame: a query panics (a wiring error of the caller, not an
//! input) and GPU-culling commands are refused (`gpu_culling` errs). The
//! oracle pass draws into a buffer it clears itself, so it works as usual.

use super::SoftBackend;
use crate::raster::{CommandResult, DepthBuffer};
use std::sync::{Arc, Mutex, PoisonError};

/// The draws of one frame of a recording backend, shared with a replaying
/// one (cloning shares).
#[derive(Clone, Debug, Default)]
pub struct DrawReplay(Arc<Mutex<Frame>>);

#[derive(Debug, Default)]
struct Frame {
    /// Each draw command's counts and the clip-space triangles it recorded
    /// (after near-plane clipping), in order.
    draws: Vec<(CommandResult, usize)>,
    /// The final depth image.
    depth: Vec<f32>,
}

impl DrawReplay {
    fn frame(&self) -> std::sync::MutexGuard<'_, Frame> {
        self.0.lock().unwrap_or_else(PoisonError::into_inner)
    }
}

/// A backend's part in a replay.
#[derive(Clone, Debug, Default)]
pub(super) enum Role {
    /// Rasterizes its own commands (the default).
    #[default]
    Own,
    /// Rasterizes, and keeps its draws' counts and final image.
    Record(DrawReplay),
    /// Rasterizes nothing: its draws' counts and image are the recording
    /// backend's; `next` is the frame's next draw to take.
    Replay { shared: DrawReplay, next: usize },
}

impl Role {
    /// A frame begins.
    pub(super) fn begin_frame(&mut self) {
        match self {
            Self::Own => {}
            Self::Record(shared) => shared.frame().draws.clear(),
            Self::Replay { next, .. } => *next = 0,
        }
    }

    /// Keeps, when recording, the next draw command's counts and recorded
    /// triangles.
    pub(super) fn keep(&self, result: CommandResult, triangles: usize) {
        if let Self::Record(shared) = self {
            shared.frame().draws.push((result, triangles));
        }
    }

    /// When replaying, takes the frame's next draw and returns the
    /// triangles the recording backend recorded for it (so that the
    /// replaying one flushes where it would have); `None` otherwise.
    ///
    /// # Panics
    /// If the recording backend made fewer draws in the frame.
    pub(super) fn next_draw(&mut self) -> Option<usize> {
        let Self::Replay { shared, next } = self else { return None };
        let triangles = shared.frame().draws.get(*next).expect("replayed more draws than were recorded").1;
        *next += 1;
        Some(triangles)
    }

    /// When replaying, the counts of the last `count` draws taken; `None`
    /// otherwise.
    pub(super) fn taken(&self, count: usize) -> Option<Vec<CommandResult>> {
        let Self::Replay { shared, next } = self else { return None };
        Some(shared.frame().draws[*next - count..*next].iter().map(|d| d.0).collect())
    }

    /// Whether queries (and anything else that reads the depth buffer
    /// during the frame) cannot be answered: when replaying.
    pub(super) fn replays(&self) -> bool {
        matches!(self, Self::Replay { .. })
    }

    /// Keeps the frame's final image `depth` when recording.
    pub(super) fn keep_image(&self, depth: &DepthBuffer) {
        if let Self::Record(shared) = self {
            depth.copy_to(&mut shared.frame().depth);
        }
    }

    /// Writes the recorded final image into `out` when replaying; false
    /// otherwise.
    pub(super) fn image(&self, out: &mut Vec<f32>) -> bool {
        let Self::Replay { shared, .. } = self else { return false };
        out.clone_from(&shared.frame().depth);
        true
    }
}

impl SoftBackend {
    /// From the next frame on, keeps every draw's counts and the final
    /// depth image in `shared`, for a backend replaying them (module
    /// documentation).
    pub fn record_draws(&mut self, shared: DrawReplay) {
        self.replay = Role::Record(shared);
    }

    /// From the next frame on, takes the draws' counts and the final depth
    /// image from `shared` instead of rasterizing: every frame must make the
    /// draws the recording backend made in it, after it, and no query,
    /// GPU-culling command or oracle (module documentation).
    pub fn replay_draws(&mut self, shared: DrawReplay) {
        self.replay = Role::Replay { shared, next: 0 };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::GpuModel;
    use glam::Vec3;
    use occlude_core::{Aabb, Backend, FrameStats, Instruments, Keyframe, Scene};

    /// Boxes one behind the other down -z, some overlapping, and the camera
    /// at the origin looking at them.
    fn boxes() -> (Scene, occlude_core::Camera) {
        let bounds: Vec<Aabb> = (0..10)
            .map(|k| {
                let c = Vec3::new(0.3 * (k % 3) as f32 - 0.3, 0.2 * (k % 2) as f32, -2.0 - 0.4 * k as f32);
                Aabb::new(c - Vec3::splat(0.35), c + Vec3::splat(0.35))
            })
            .collect();
        let key = Keyframe { time: 0.0, position: Vec3::ZERO, target: -Vec3::Z, fov_y_deg: 60.0 };
        (Scene::from_bounds("boxes", &bounds).unwrap(), key.camera(4.0 / 3.0, 0.1, 100.0))
    }

    /// A backend replaying another's draws gives, frame after frame, the
    /// statistics (all but the wall clock) and the depth image of one
    /// rasterizing the same draws itself, bit for bit: with a bounded
    /// driver queue, flushes and rasterizing ahead every few triangles, and
    /// queries and their waits between the recording backend's draws.
    #[test]
    fn a_replayed_frame_has_the_figures_and_image_of_a_rasterized_one() {
        let (scene, camera) = boxes();
        let bounded = GpuModel { gpu_draw_call_us: 40.0, driver_queue_us: 60.0, ..GpuModel::modern() };
        for model in [GpuModel::gpu_2004(), bounded] {
            let backend = || {
                let mut b = SoftBackend::new(&scene, 97, 71, model.clone());
                (b.raster_triangles, b.flush_triangles) = (13, 29);
                b
            };
            let shared = DrawReplay::default();
            let (mut recording, mut replaying, mut plain) = (backend(), backend(), backend());
            recording.record_draws(shared.clone());
            replaying.replay_draws(shared);
            let frames: [&[&[u32]]; 3] = [&[&[0, 1], &[5], &[2, 3, 4]], &[&[9, 8, 7], &[6]], &[&[1], &[1, 2]]];
            for draws in frames {
                recording.begin_frame(&camera);
                for (k, d) in draws.iter().enumerate() {
                    let query = recording.issue_query(&[scene.instances[k].bounds]);
                    recording.draw(d);
                    if k % 2 == 0 {
                        recording.result(query);
                    }
                }
                recording.end_frame();
                let frame = |b: &mut SoftBackend| {
                    b.begin_frame(&camera);
                    draws.iter().for_each(|d| b.draw(d));
                    let stats = FrameStats { wall_ms: 0.0, ..b.end_frame() };
                    let mut image = Vec::new();
                    b.depth_image(&mut image);
                    (stats, image.iter().map(|d| d.to_bits()).collect::<Vec<_>>())
                };
                let (replayed, rasterized) = (frame(&mut replaying), frame(&mut plain));
                assert!(rasterized.0.fragments > 0 && rasterized.1.iter().any(|&d| d != 1.0f32.to_bits()));
                assert_eq!(replayed, rasterized);
            }
        }
    }

    /// A replaying backend refuses GPU-culling commands.
    #[test]
    fn a_replaying_backend_runs_no_culling_commands() {
        let (scene, _) = boxes();
        let mut backend = SoftBackend::new(&scene, 32, 24, GpuModel::modern());
        backend.replay_draws(DrawReplay::default());
        assert!(backend.gpu_culling().is_err());
    }
}
