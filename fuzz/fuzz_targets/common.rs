//! What every importer fuzz target checks.

use occlude_scenes::import::{import_bytes, ModelFormat};
use occlude_scenes::{AutoPath, ImportOptions};
use std::path::Path;

/// Imports `data` as the model `name` of `format`, in a directory that does
/// not exist (so that files it refers to are missing), with both automatic
/// paths and a small split size. An error is fine; a scene must validate and
/// have finite instance boxes and a finite walkthrough whose times increase.
pub fn check(data: &[u8], name: &str, format: ModelFormat) {
    let path = Path::new("/nonexistent-occlude-fuzz").join(name);
    for auto_path in [AutoPath::Orbit, AutoPath::Walk] {
        let options = ImportOptions { split_triangles: 64, auto_path };
        let Ok(imported) = import_bytes(&path, data, format, &options) else { return };
        let scene = imported.scene;
        scene.validate().expect("an imported scene validates");
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
