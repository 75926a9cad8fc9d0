//! What every importer fuzz target checks.

use occlude_core::MotionError;
use occlude_scenes::import::{import_bytes, ModelFormat};
use occlude_scenes::{AutoPath, ImportOptions};
use std::path::Path;

/// Imports `data` as the model `name` of `format`, in a directory that does
/// not exist (so that files it refers to are missing), with both automatic
/// paths and a small split size. An error is fine; a scene must validate and
/// have finite instance boxes and a finite walkthrough whose times increase,
/// and its animation, if any, must move only instances the scene has, at any
/// time (a move may still be refused as not finite).
pub fn check(data: &[u8], name: &str, format: ModelFormat) {
    let path = Path::new("/nonexistent-occlude-fuzz").join(name);
    for auto_path in [AutoPath::Orbit, AutoPath::Walk] {
        let options = ImportOptions { split_triangles: 64, auto_path };
        let Ok(imported) = import_bytes(&path, data, format, &options) else { return };
        let scene = imported.scene;
        scene.validate().expect("an imported scene validates");
        if let Some(animation) = &imported.animation {
            let d = animation.duration();
            for t in [-1.0, 0.0, 0.3 * d, 0.5 * d, d, 2.5 * d + 0.1, 1e30] {
                let mut moving = scene.clone();
                if let Err(e) = moving.apply(&animation.changes_at(t)) {
                    assert!(matches!(e, MotionError::NonFiniteTransform { .. }), "at {t} s: {e}");
                }
            }
        }
        for (i, instance) in scene.instances.iter().enumerate() {
            assert!(instance.bounds.min.is_finite() && instance.bounds.max.is_finite(), "instance {i}: {instance:?}");
        }
        let keys = &scene.path.keyframes;
        assert!(!keys.is_empty(), "an imported scene has a walkthrough");
        for key in keys {
            assert!(key.position.is_finite() && key.target.is_finite() && key.time.is_finite(), "keyframe {key:?}");
        }
        assert!(keys.windows(2).all(|w| w[0].time < w[1].time), "keyframe times increase: {keys:?}");
    }
}
