//! Fuzzes the camera-path reader (`bench --camera-path`, `view
//! --camera-path`). Any input may be refused with an error; none may panic
//! or hang, and a path that is accepted must give cameras that can render:
//! every keyframe in range, a frame count that is bounded before any frame
//! is made, and finite cameras apart from their targets.

#![no_main]

use occlude_bench::camera_path::{cameras, check_keyframe, parse, MIN_TARGET_DISTANCE};
use occlude_bench::limits::MAX_FRAMES;
use occlude_core::Sampling;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let Ok(path) = parse(text, "fuzz.json") else { return };
    for k in &path.keyframes {
        check_keyframe(k).expect("an accepted keyframe is in range");
    }
    assert!(path.keyframes.windows(2).all(|w| w[0].time < w[1].time), "times increase");
    // The whole path at the highest frame rate is counted, not made.
    let _ = path.frame_count(Sampling::Rate { fps: 1000.0, limit: None });
    for sampling in [Sampling::Rate { fps: 30.0, limit: Some(64) }, Sampling::Spread(17)] {
        let Ok(frames) = cameras(&path, sampling, 4.0 / 3.0, 0.25, 1000.0) else { continue };
        assert!(frames.len() <= MAX_FRAMES);
        for c in &frames {
            assert!(c.position.is_finite() && c.target.is_finite() && c.fov_y_deg.is_finite(), "{c:?}");
            assert!(c.position.distance(c.target) >= MIN_TARGET_DISTANCE, "{c:?}");
        }
    }
});
