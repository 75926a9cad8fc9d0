//! The viewer's frames with occlude's culling (`hiz`, `roc`, `ioc` and
//! `auto` GPU-driven, `chcpp` query-driven) are the frames without culling, bit
//! for bit (colour and depth), over frames of motion: a generated building
//! with people walking and doors opening (`crowd`), and an animated glTF
//! file written here. Runs on any adapter (lavapipe in CI, with
//! `OCCLUDE_REQUIRE_GPU=1`); skipped with a message where there is none,
//! unless `OCCLUDE_REQUIRE_GPU=1`. Bad input makes the binary say why and
//! exit with 1.

use gltf_viewer::{open_device, start, Fly, Offscreen, Renderer};
use occlude::scenes::{load_moving, ImportOptions, OwnMotion, Size};
use occlude::Scene;
use std::process::Command;

/// Frames rendered per method.
const FRAMES: u32 = 5;
/// Image width and height.
const SIZE: u32 = 256;
/// The methods compared with culling off.
const METHODS: [&str; 5] = ["hiz", "chcpp", "roc", "ioc", "auto"];

/// A device for test `test`, or `None` (after saying why) when there is no
/// adapter and the environment does not require one.
fn device(test: &str) -> Option<(wgpu::Device, wgpu::Queue)> {
    match open_device() {
        Ok(pair) => Some(pair),
        Err(e) if std::env::var("OCCLUDE_REQUIRE_GPU").is_ok_and(|v| v == "1") => {
            panic!("{test}: OCCLUDE_REQUIRE_GPU=1 but no GPU adapter could be opened: {e}")
        }
        Err(e) => {
            eprintln!("skipping {test}: no GPU adapter ({e})");
            None
        }
    }
}

/// Each frame's colour and depth images and instances drawn, culling with
/// `culling` (`off` or a method): frame k at k * `step` seconds of the
/// motion and of the walkthrough.
fn frames(
    device: &(wgpu::Device, wgpu::Queue),
    scene: &Scene,
    motion: &Option<OwnMotion>,
    culling: &str,
    step: f32,
) -> Vec<(Vec<u8>, Vec<f32>, u64)> {
    let (device, queue) = device.clone();
    let target = Offscreen::new(&device, SIZE, SIZE);
    let first = start(scene);
    let mut renderer = Renderer::new(device, queue, scene.clone(), motion.clone(), Offscreen::FORMAT);
    renderer.set_culling((culling != "off").then(|| culling.parse().unwrap())).unwrap();
    (0..FRAMES)
        .map(|k| {
            let t = k as f32 * step;
            renderer.set_time(t).unwrap();
            let fly = Fly::from_keyframe(&scene.path.at(first.time + t).unwrap_or(first));
            let projection = fly.projection(1.0, &renderer.scene().bounds());
            renderer.render(&target.view(), fly.view(), projection).unwrap();
            let drawn = renderer.drawn().unwrap().instances;
            (target.image(&renderer).unwrap(), renderer.depth_image().unwrap(), drawn)
        })
        .collect()
}

/// Renders `scene` moving with culling off and with each of [`METHODS`],
/// and checks every frame's images are the same; returns each method's
/// instances drawn per frame, culling off's first.
fn culling_keeps_the_frames(
    device: &(wgpu::Device, wgpu::Queue),
    scene: &Scene,
    motion: &Option<OwnMotion>,
    step: f32,
) -> Vec<Vec<u64>> {
    let reference = frames(device, scene, motion, "off", step);
    for (k, (color, _, _)) in reference.iter().enumerate() {
        let background = &color[..4];
        let drawn = color.chunks(4).filter(|p| p != &background).count();
        assert!(drawn > color.len() / 4 / 20, "frame {k}: the image is nearly empty ({drawn} pixels)");
    }
    let mut counts = vec![reference.iter().map(|f| f.2).collect()];
    for method in METHODS {
        let got = frames(device, scene, motion, method, step);
        for (k, ((color, depth, _), (want_color, want_depth, _))) in got.iter().zip(&reference).enumerate() {
            let colours = color.chunks(4).zip(want_color.chunks(4)).filter(|(a, b)| a != b).count();
            assert_eq!(colours, 0, "{method}, frame {k}: colour pixels differ from culling off");
            let depths = depth.iter().zip(want_depth).filter(|(a, b)| a.to_bits() != b.to_bits()).count();
            assert_eq!(depths, 0, "{method}, frame {k}: depth pixels differ from culling off");
        }
        counts.push(got.iter().map(|f| f.2).collect());
    }
    counts
}

/// The generated building with people and doors: many meshes, instances
/// moving, hidden and shown again. Culling draws fewer instances than
/// culling off once `hiz` has warmed up (third frame on).
#[test]
fn culling_keeps_the_frames_of_a_moving_building() {
    let Some(device) = device("culling_keeps_the_frames_of_a_moving_building") else { return };
    let (scene, motion) = load_moving("crowd", Size::Small, 1, &ImportOptions::default()).unwrap();
    assert!(scene.meshes.len() > 5 && motion.is_some());
    let counts = culling_keeps_the_frames(&device, &scene, &motion, 0.5);
    for (method, drawn) in METHODS.iter().zip(&counts[1..]) {
        for k in 2..FRAMES as usize {
            assert!(drawn[k] < counts[0][k], "{method}, frame {k}: drew {} of {}", drawn[k], counts[0][k]);
        }
    }
}

/// A glTF file whose one animation carries a box sideways from behind a
/// wall, past boxes of two materials.
#[test]
fn culling_keeps_the_frames_of_an_animated_gltf_file() {
    let Some(device) = device("culling_keeps_the_frames_of_an_animated_gltf_file") else { return };
    let dir = tempfile::tempdir().unwrap();
    let file = write_animated_gltf(dir.path());
    let (scene, motion) = load_moving(file.to_str().unwrap(), Size::Small, 1, &ImportOptions::default()).unwrap();
    let Some(OwnMotion::Animation(animation)) = &motion else { panic!("the file's animation was not imported") };
    assert_eq!(animation.moved().count(), 1);
    culling_keeps_the_frames(&device, &scene, &motion, 0.5);
}

/// Writes `animated.gltf` and its buffer into `dir`: a floor, a wall, a
/// grid of boxes behind it, and a box moving from one side to the other in
/// two seconds.
fn write_animated_gltf(dir: &std::path::Path) -> std::path::PathBuf {
    let corners: Vec<f32> = (0..8).flat_map(|c: u32| [c & 1, c >> 1 & 1, c >> 2 & 1].map(|b| b as f32 - 0.5)).collect();
    let faces: [u16; 36] =
        [0, 1, 3, 0, 3, 2, 4, 6, 7, 4, 7, 5, 0, 4, 5, 0, 5, 1, 2, 3, 7, 2, 7, 6, 0, 2, 6, 0, 6, 4, 1, 5, 7, 1, 7, 3];
    let times = [0.0f32, 2.0];
    let places = [-6.0f32, 0.5, -2.0, 6.0, 0.5, -2.0];
    let mut bin: Vec<u8> = corners.iter().flat_map(|f| f.to_le_bytes()).collect();
    bin.extend(faces.iter().flat_map(|i| i.to_le_bytes()));
    bin.extend(times.iter().chain(&places).flat_map(|f| f.to_le_bytes()));
    std::fs::write(dir.join("animated.bin"), &bin).unwrap();
    let node = |mesh: u32, [x, y, z]: [f32; 3], [sx, sy, sz]: [f32; 3]| {
        format!(r#"{{"mesh": {mesh}, "translation": [{x}, {y}, {z}], "scale": [{sx}, {sy}, {sz}]}}"#)
    };
    let mut nodes = vec![
        node(0, [0.0, -0.1, -3.0], [20.0, 0.2, 20.0]),
        node(0, [0.0, 1.0, 0.0], [6.0, 2.0, 0.3]),
        node(1, [-6.0, 0.5, -2.0], [1.0, 1.0, 1.0]),
    ];
    for k in 0..12 {
        let (x, z) = ((k % 4) as f32 * 2.0 - 3.0, -4.0 - (k / 4) as f32 * 2.0);
        nodes.push(node(k % 2, [x, 0.75, z], [0.8, 1.5, 0.8]));
    }
    let roots: Vec<String> = (0..nodes.len()).map(|k| k.to_string()).collect();
    let json = format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "buffers": [{{"uri": "animated.bin", "byteLength": {len}}}],
  "bufferViews": [
    {{"buffer": 0, "byteOffset": 0, "byteLength": 96}},
    {{"buffer": 0, "byteOffset": 96, "byteLength": 72}},
    {{"buffer": 0, "byteOffset": 168, "byteLength": 8}},
    {{"buffer": 0, "byteOffset": 176, "byteLength": 24}}
  ],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 8, "type": "VEC3", "min": [-0.5, -0.5, -0.5], "max": [0.5, 0.5, 0.5]}},
    {{"bufferView": 1, "componentType": 5123, "count": 36, "type": "SCALAR"}},
    {{"bufferView": 2, "componentType": 5126, "count": 2, "type": "SCALAR", "min": [0.0], "max": [2.0]}},
    {{"bufferView": 3, "componentType": 5126, "count": 2, "type": "VEC3"}}
  ],
  "materials": [{{}}, {{}}],
  "meshes": [
    {{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1, "material": 0}}]}},
    {{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1, "material": 1}}]}}
  ],
  "nodes": [{nodes}],
  "scenes": [{{"nodes": [{roots}]}}],
  "scene": 0,
  "animations": [{{
    "samplers": [{{"input": 2, "output": 3, "interpolation": "LINEAR"}}],
    "channels": [{{"sampler": 0, "target": {{"node": 2, "path": "translation"}}}}]
  }}]
}}"#,
        len = bin.len(),
        nodes = nodes.join(",\n    "),
        roots = roots.join(", "),
    );
    let file = dir.join("animated.gltf");
    std::fs::write(&file, json).unwrap();
    file
}

/// A missing file and a broken model are errors the binary names, exiting
/// with 1 (no window is opened).
#[test]
fn bad_input_is_an_error_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let broken = dir.path().join("broken.gltf");
    std::fs::write(&broken, "{ not json").unwrap();
    let missing = dir.path().join("missing.glb");
    for file in [&missing, &broken] {
        let out = Command::new(env!("CARGO_BIN_EXE_gltf-viewer")).arg(file).output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{}: {stderr}", file.display());
        assert!(stderr.contains("gltf-viewer:") && stderr.contains(file.to_str().unwrap()), "{stderr}");
    }
}
