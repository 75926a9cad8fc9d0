//! glTF node animations that the tests write themselves: values at known
//! times for every interpolation, clamping, the node hierarchy, and an
//! error naming the animation for every kind of broken animation data.

use base64::Engine;
use glam::{Mat4, Quat, Vec3};
use occlude_core::InstanceChange;
use occlude_scenes::import::{import_bytes, Imported, ModelFormat};
use occlude_scenes::{ImportOptions, LoadError, SceneAnimation};
use serde_json::{json, Value};
use std::path::Path;

/// A glTF document over one buffer: a unit cube mesh (mesh 0, two
/// primitives of two materials: two instances per node) and the accessors
/// that animations add.
struct Animated {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Animated {
    fn new() -> Self {
        let mut g = Animated { bin: vec![], views: vec![], accessors: vec![] };
        let corners: Vec<f32> =
            (0..8).flat_map(|c| [c & 1, c >> 1 & 1, c >> 2 & 1].map(|bit| bit as f32 - 0.5)).collect();
        g.floats(&corners, "VEC3");
        let faces: [u16; 36] = [
            0, 1, 3, 0, 3, 2, 4, 6, 7, 4, 7, 5, 0, 4, 5, 0, 5, 1, 2, 3, 7, 2, 7, 6, 0, 2, 6, 0, 6, 4, 1, 5, 7, 1, 7, 3,
        ];
        let bytes: Vec<u8> = faces.iter().flat_map(|i| i.to_le_bytes()).collect();
        g.accessor(&bytes, json!({"componentType": 5123, "count": 36, "type": "SCALAR"}));
        g
    }

    /// An accessor over `bytes` with the fields of `accessor`; its index.
    fn accessor(&mut self, bytes: &[u8], mut accessor: Value) -> usize {
        self.bin.resize(self.bin.len().next_multiple_of(4), 0);
        self.views.push(json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()}));
        self.bin.extend_from_slice(bytes);
        accessor["bufferView"] = json!(self.views.len() - 1);
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    /// A float accessor of `kind` (`SCALAR`, `VEC3`, ...) over `values`;
    /// scalars get the bounds glTF requires of key times.
    fn floats(&mut self, values: &[f32], kind: &str) -> usize {
        let bytes: Vec<u8> = values.iter().flat_map(|f| f.to_le_bytes()).collect();
        let width = match kind {
            "SCALAR" => 1,
            "VEC2" => 2,
            "VEC3" => 3,
            _ => 4,
        };
        let mut accessor = json!({"componentType": 5126, "count": values.len() / width, "type": kind});
        let finite: Vec<f32> = values.iter().copied().filter(|v| v.is_finite()).collect();
        if kind == "SCALAR" || kind == "VEC3" {
            let bound = |pick: fn(f32, f32) -> f32| -> Vec<f32> {
                (0..width).map(|c| finite.iter().skip(c).step_by(width).copied().reduce(pick).unwrap_or(0.0)).collect()
            };
            accessor["min"] = json!(bound(f32::min));
            accessor["max"] = json!(bound(f32::max));
        }
        self.accessor(&bytes, accessor)
    }

    /// A sampler of `interpolation` over key `times` and `values` of `kind`.
    fn sampler(&mut self, times: &[f32], values: &[f32], kind: &str, interpolation: &str) -> Value {
        let input = self.floats(times, "SCALAR");
        let output = self.floats(values, kind);
        json!({"input": input, "output": output, "interpolation": interpolation})
    }

    /// The document of `nodes` (roots: those no other node has as a child)
    /// and the one animation `walk` of `samplers` and `channels` (each
    /// `[sampler, node, path]`).
    fn document(self, nodes: Value, samplers: Vec<Value>, channels: &[(usize, usize, &str)]) -> Value {
        let children: Vec<u64> = nodes
            .as_array()
            .unwrap()
            .iter()
            .flat_map(|n| n["children"].as_array().cloned().unwrap_or_default())
            .map(|c| c.as_u64().unwrap())
            .collect();
        let roots: Vec<usize> =
            (0..nodes.as_array().unwrap().len()).filter(|&n| !children.contains(&(n as u64))).collect();
        let channels: Vec<Value> = channels
            .iter()
            .map(|&(sampler, node, path)| json!({"sampler": sampler, "target": {"node": node, "path": path}}))
            .collect();
        let data = base64::engine::general_purpose::STANDARD.encode(&self.bin);
        json!({
            "asset": {"version": "2.0"},
            "scene": 0,
            "scenes": [{"nodes": roots}],
            "nodes": nodes,
            "meshes": [{"primitives": [
                {"attributes": {"POSITION": 0}, "indices": 1, "material": 0},
                {"attributes": {"POSITION": 0}, "indices": 1, "material": 1}
            ]}],
            "materials": [{"name": "a"}, {"name": "b"}],
            "accessors": self.accessors,
            "bufferViews": self.views,
            "buffers": [{"byteLength": self.bin.len(), "uri": format!("data:application/octet-stream;base64,{data}")}],
            "animations": [{"name": "walk", "samplers": samplers, "channels": channels}],
        })
    }
}

fn import(document: &Value) -> Result<Imported, LoadError> {
    let bytes = serde_json::to_vec(document).unwrap();
    import_bytes(Path::new("animated.gltf"), &bytes, ModelFormat::Gltf, &ImportOptions::default())
}

/// The transform each change of `animation` at `t` gives its instance.
fn transforms_at(animation: &SceneAnimation, t: f32) -> Vec<(u32, Mat4)> {
    animation
        .changes_at(t)
        .into_iter()
        .map(|c| match c {
            InstanceChange::Move { instance, transform } => (instance, transform),
            other => panic!("an animation only moves: {other:?}"),
        })
        .collect()
}

fn assert_near(a: Mat4, b: Mat4) {
    assert!(a.abs_diff_eq(b, 1e-5), "{a} != {b}");
}

/// Three cubes: node 0 slides along x (LINEAR, keys at 1 s and 2 s), node 1
/// doubles in size at 1 s (STEP), node 2 rises by a cubic spline with flat
/// tangents (keys at 0 s and 2 s); a fourth, node 3, stands still.
fn three_movers() -> Value {
    let mut g = Animated::new();
    let samplers = vec![
        g.sampler(&[1.0, 2.0], &[0.0, 0.0, 0.0, 4.0, 0.0, 0.0], "VEC3", "LINEAR"),
        g.sampler(&[0.0, 1.0], &[1.0, 1.0, 1.0, 2.0, 2.0, 2.0], "VEC3", "STEP"),
        g.sampler(
            &[0.0, 2.0],
            &[0., 0., 0., 0., 0., 0., 0., 0., 0., 0., 0., 0., 0., 4., 0., 0., 0., 0.],
            "VEC3",
            "CUBICSPLINE",
        ),
    ];
    let nodes = json!([
        {"mesh": 0},
        {"mesh": 0, "translation": [0, 0, 5]},
        {"mesh": 0, "translation": [0, 0, 10]},
        {"mesh": 0, "translation": [0, 0, 15]},
    ]);
    g.document(nodes, samplers, &[(0, 0, "translation"), (1, 1, "scale"), (2, 2, "translation")])
}

#[test]
fn linear_step_and_cubic_spline_channels_place_their_instances_at_known_times() {
    let imported = import(&three_movers()).unwrap();
    let animation = imported.animation.expect("the file is animated");
    assert_eq!(animation.duration(), 2.0);
    // Two instances per node (two primitives); node 3's never move.
    assert_eq!(animation.moved().collect::<Vec<_>>(), [0, 1, 2, 3, 4, 5]);
    let at = |t: f32| transforms_at(&animation, t);
    let translated = |x: f32, y: f32, z: f32| Mat4::from_translation(Vec3::new(x, y, z));
    let scaled = |s: f32| Mat4::from_scale_rotation_translation(Vec3::splat(s), Quat::IDENTITY, Vec3::Z * 5.0);
    // Halfway between keys; before the first key of node 0 (clamped).
    let half = at(1.5);
    assert_near(half[0].1, translated(2.0, 0.0, 0.0));
    assert_near(half[1].1, translated(2.0, 0.0, 0.0));
    assert_near(half[2].1, scaled(2.0));
    assert_near(at(0.5)[0].1, translated(0.0, 0.0, 0.0));
    assert_near(at(0.5)[2].1, scaled(1.0));
    // Cubic spline with flat tangents: 3s² - 2s³ of the rise, 0.5 at 1 s;
    // the animated translation replaces the node's own.
    assert_near(at(1.0)[4].1, translated(0.0, 2.0, 0.0));
    // Time loops over the 2 s duration: 3.5 s is 1.5 s.
    assert_eq!(at(3.5), half);
    // The scene itself is built in its rest pose.
    assert_near(imported.scene.instances[2].transform, scaled(1.0));
}

#[test]
fn children_of_an_animated_node_move_with_it() {
    let mut g = Animated::new();
    let quarter = Quat::from_rotation_y(std::f32::consts::FRAC_PI_2).to_array();
    let samplers = vec![g.sampler(&[0.0, 1.0], &[&[0.0, 0.0, 0.0, 1.0][..], &quarter].concat(), "VEC4", "LINEAR")];
    let nodes = json!([
        {"translation": [0, 1, 0], "children": [1]},
        {"rotation": [0, 0, 0, 1], "translation": [0, 0, 2], "children": [2]},
        {"mesh": 0, "translation": [3, 0, 0]},
        {"mesh": 0, "translation": [0, 0, -9]},
    ]);
    let document = g.document(nodes, samplers, &[(0, 1, "rotation")]);
    let animation = import(&document).unwrap().animation.unwrap();
    // Node 2 (instances 0, 1) hangs below animated node 1; node 3 does not.
    assert_eq!(animation.moved().collect::<Vec<_>>(), [0, 1]);
    let expected = Mat4::from_translation(Vec3::new(0.0, 1.0, 2.0))
        * Mat4::from_quat(Quat::from_rotation_y(std::f32::consts::FRAC_PI_4))
        * Mat4::from_translation(Vec3::X * 3.0);
    assert_near(transforms_at(&animation, 0.5)[1].1, expected);
}

#[test]
fn weights_channels_are_ignored_with_a_warning() {
    let mut g = Animated::new();
    let samplers = vec![g.sampler(&[0.0, 1.0], &[0.0, 1.0], "SCALAR", "LINEAR")];
    let document = g.document(json!([{"mesh": 0}]), samplers, &[(0, 0, "weights")]);
    let imported = import(&document).unwrap();
    assert!(imported.animation.is_none());
    assert!(imported.warnings.iter().any(|w| w.contains("weights channels are ignored")), "{:?}", imported.warnings);
}

#[test]
fn broken_animations_are_errors_naming_the_file_and_the_animation() {
    let translation = |times: &[f32], values: &[f32], kind: &str, interpolation: &str| {
        let mut g = Animated::new();
        let samplers = vec![g.sampler(times, values, kind, interpolation)];
        g.document(json!([{"mesh": 0}]), samplers, &[(0, 0, "translation")])
    };
    let with = |mut document: Value, pointer: &str, value: Value| {
        let (object, key) = pointer.rsplit_once('/').unwrap();
        document.pointer_mut(object).unwrap()[key] = value;
        document
    };
    let valid = translation(&[0.0, 1.0], &[0.0; 6], "VEC3", "LINEAR");
    let cases = [
        (translation(&[0.0, 1.0], &[0.0; 9], "VEC3", "LINEAR"), "2 key times but 3 values"),
        (translation(&[0.0, 1.0], &[0.0; 6], "VEC3", "CUBICSPLINE"), "CubicSpline needs 3 per key"),
        (translation(&[0.0, 1.0, 1.0], &[0.0; 9], "VEC3", "LINEAR"), "key time 2 (1) does not increase"),
        (translation(&[0.0, f32::NAN], &[0.0; 6], "VEC3", "LINEAR"), "key time 1 is not finite"),
        (
            translation(&[0.0, 1.0], &[0.0, 0.0, 0.0, f32::INFINITY, 0.0, 0.0], "VEC3", "LINEAR"),
            "value 1 is not finite",
        ),
        (translation(&[0.0, 1.0], &[0.0; 4], "VEC2", "LINEAR"), "not F32 Vec3"),
        (with(valid.clone(), "/animations/0/channels/0/target/node", json!(7)), "targets node 7, which does not exist"),
        (with(valid.clone(), "/animations/0/channels/0/target/path", json!("colour")), "unknown path"),
        (with(valid.clone(), "/animations/0/channels/0/sampler", json!(3)), "sampler 3, which does not exist"),
        (with(valid.clone(), "/accessors/3/componentType", json!(5123)), "not F32 Vec3"),
        (with(valid.clone(), "/accessors/2/type", json!("VEC2")), "not F32 Scalar"),
        (
            with(valid.clone(), "/nodes/0/matrix", json!([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1])),
            "has a matrix",
        ),
        (with(valid, "/animations/0/samplers/0/interpolation", json!("SMOOTH")), "unknown interpolation"),
    ];
    for (document, problem) in cases {
        let error = import(&document).expect_err(problem);
        let message = error.to_string();
        assert!(matches!(error, LoadError::Invalid { .. }) && error.is_input_error(), "{problem}: {error:?}");
        assert!(message.starts_with("animated.gltf: animation 0 'walk'"), "{problem}: {message}");
        assert!(message.contains(problem), "{problem}: {message}");
    }
}
