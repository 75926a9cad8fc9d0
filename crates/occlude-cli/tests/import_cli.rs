//! `occlude bench` on imported model files: a small glTF room runs with every
//! method exact, still and animated, and a broken model is a usage error
//! (exit code 2) naming it.

use std::path::{Path, PathBuf};
use std::process::Command;

/// A unit cube centred on the origin: 8 float positions then 36 u16 indices,
/// base64 (168 bytes).
const CUBE: &str = "AAAAvwAAAL8AAAC/AAAAPwAAAL8AAAC/AAAAPwAAAD8AAAC/AAAAvwAAAD8AAAC/AAAAvwAAAL8AAAA/AAAAPwAAAL8AAAA/\
AAAAPwAAAD8AAAA/AAAAvwAAAD8AAAA/AAACAAEAAAADAAIABAAFAAYABAAGAAcAAAABAAUAAAAFAAQAAwAHAAYAAwAGAAIAAAAEAAcAAAAHAAMA\
AQACAAYAAQAGAAUA";

/// A 10 x 3 x 10 m room (floor, four walls) with three crates, one cube mesh
/// instanced eight times.
fn room_gltf() -> String {
    let boxes: [([f32; 3], [f32; 3]); 8] = [
        ([5.0, -0.05, 5.0], [10.0, 0.1, 10.0]),
        ([0.1, 1.5, 5.0], [0.2, 3.0, 10.0]),
        ([9.9, 1.5, 5.0], [0.2, 3.0, 10.0]),
        ([5.0, 1.5, 0.1], [10.0, 3.0, 0.2]),
        ([5.0, 1.5, 9.9], [10.0, 3.0, 0.2]),
        ([2.0, 0.5, 5.0], [1.0, 1.0, 1.0]),
        ([5.0, 0.5, 5.0], [1.0, 1.0, 1.0]),
        ([8.0, 0.5, 5.0], [1.0, 1.0, 1.0]),
    ];
    let nodes: Vec<String> =
        boxes.iter().map(|(t, s)| format!(r#"{{"mesh":0,"translation":{t:?},"scale":{s:?}}}"#)).collect();
    let roots: Vec<String> = (0..boxes.len()).map(|i| i.to_string()).collect();
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[{}]}}],"nodes":[{}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":8,"type":"VEC3","min":[-0.5,-0.5,-0.5],"max":[0.5,0.5,0.5]}},
{{"bufferView":1,"componentType":5123,"count":36,"type":"SCALAR"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":96}},{{"buffer":0,"byteOffset":96,"byteLength":72}}],
"buffers":[{{"byteLength":168,"uri":"data:application/octet-stream;base64,{CUBE}"}}]}}"#,
        roots.join(","),
        nodes.join(",")
    )
}

/// The room of [`room_gltf`] animated (animation 0, `move`): its middle
/// crate (node 6) rises and falls (LINEAR), and a cart (node 8, no mesh)
/// carries a crate (node 9) across the room (CUBICSPLINE, flat tangents),
/// over 2 s. The keys are in the external buffer `anim.bin`, returned
/// beside the JSON.
fn animated_room_gltf() -> (String, Vec<u8>) {
    let times = [0.0f32, 1.0, 2.0];
    let rise = [5.0f32, 0.5, 5.0, 5.0, 2.5, 5.0, 5.0, 0.5, 5.0];
    let (a, b) = ([2.0f32, 0.0, 2.0], [8.0f32, 0.0, 8.0]);
    let zero = [0.0f32; 3];
    let carry: Vec<f32> = [a, b, a].iter().flat_map(|v| [zero, *v, zero]).flatten().collect();
    let bin: Vec<u8> = times.iter().chain(&rise).chain(&carry).flat_map(|f| f.to_le_bytes()).collect();
    let json = room_gltf()
        .replacen(r#""scenes":[{"nodes":["#, r#""scenes":[{"nodes":[8,"#, 1)
        .replace(
            r#"{"mesh":0,"translation":[8.0, 0.5, 5.0],"scale":[1.0, 1.0, 1.0]}]"#,
            r#"{"mesh":0,"translation":[8.0, 0.5, 5.0],"scale":[1.0, 1.0, 1.0]},
{"name":"cart","translation":[2.0, 0.0, 2.0],"children":[9]},{"mesh":0,"translation":[0.0, 0.5, 0.0]}]"#,
        )
        .replace(
            r#"{"bufferView":1,"componentType":5123,"count":36,"type":"SCALAR"}]"#,
            r#"{"bufferView":1,"componentType":5123,"count":36,"type":"SCALAR"},
{"bufferView":2,"componentType":5126,"count":3,"type":"SCALAR","min":[0],"max":[2]},
{"bufferView":3,"componentType":5126,"count":3,"type":"VEC3"},
{"bufferView":4,"componentType":5126,"count":9,"type":"VEC3"}]"#,
        )
        .replace(
            r#"{"buffer":0,"byteOffset":96,"byteLength":72}]"#,
            r#"{"buffer":0,"byteOffset":96,"byteLength":72},{"buffer":1,"byteOffset":0,"byteLength":12},
{"buffer":1,"byteOffset":12,"byteLength":36},{"buffer":1,"byteOffset":48,"byteLength":108}]"#,
        )
        .replace(
            r#""}]}"#,
            r#""},{"byteLength":156,"uri":"anim.bin"}],
"animations":[{"name":"move","samplers":[{"input":2,"output":3},{"input":2,"output":4,"interpolation":"CUBICSPLINE"}],
"channels":[{"sampler":0,"target":{"node":6,"path":"translation"}},{"sampler":1,"target":{"node":8,"path":"translation"}}]}]}"#,
        );
    (json, bin)
}

fn occlude(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_occlude")).args(args).output().expect("occlude runs")
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn bench_runs_an_imported_gltf_room_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let room = write(dir.path(), "room.gltf", &room_gltf());
    let json = dir.path().join("out.json");
    for auto_path in ["orbit", "walk"] {
        let out = occlude(&[
            "bench",
            "--scene",
            room.to_str().unwrap(),
            "--frames",
            "5",
            "--resolution",
            "160x120",
            "--auto-path",
            auto_path,
            "--json",
            json.to_str().unwrap(),
        ]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{auto_path}: {stderr}");
        assert!(!stderr.contains("warning"), "{auto_path}: the room has free space to walk: {stderr}");
        let report: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
        let methods = report["methods"].as_array().expect("methods");
        assert!(methods.len() >= 2);
        for m in methods {
            assert_eq!(m["missing_pixels"], 0, "{auto_path}: {m}");
            assert_eq!(m["per_frame"].as_array().map(Vec::len), Some(5));
        }
    }
}

#[test]
fn bench_plays_an_animated_gltf_exactly_and_broken_animations_exit_with_2() {
    let dir = tempfile::tempdir().unwrap();
    let (json, bin) = animated_room_gltf();
    std::fs::write(dir.path().join("anim.bin"), bin).unwrap();
    let room = write(dir.path(), "animated.gltf", &json);
    let out_json = dir.path().join("out.json");
    let args = ["--frames", "12", "--resolution", "160x120", "--json", out_json.to_str().unwrap()];
    let out = occlude(&[&["bench", "--scene", room.to_str().unwrap()][..], &args].concat());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(&out_json).unwrap()).unwrap();
    for m in report["methods"].as_array().expect("methods") {
        assert_eq!(m["missing_pixels"], 0, "{m}");
        // Two crates move: the rising one and the carried one.
        assert_eq!(m["instances_moved_per_frame"].as_f64(), Some(2.0), "{m}");
    }
    let broken =
        write(dir.path(), "broken.gltf", &json.replace(r#""count":9,"type":"VEC3""#, r#""count":6,"type":"VEC3""#));
    let out = occlude(&["bench", "--scene", broken.to_str().unwrap(), "--frames", "2", "--resolution", "64x48"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("broken.gltf: animation 0 'move': channel 1: 3 key times but 6 values"), "{stderr}");
}

#[test]
fn bench_replays_a_camera_path_file() {
    let dir = tempfile::tempdir().unwrap();
    let room = write(dir.path(), "room.gltf", &room_gltf());
    let path = write(
        dir.path(),
        "path.json",
        r#"{"keyframes":[{"time":0,"position":[1,1.7,1],"target":[9,1.7,9],"fov_y_deg":60},
                         {"time":2,"position":[9,1.7,1],"target":[1,1.7,9],"fov_y_deg":60}]}"#,
    );
    let args = ["bench", "--scene", room.to_str().unwrap(), "--frames", "3", "--resolution", "80x60"];
    let out = occlude(&[&args[..], &["--camera-path", path.to_str().unwrap()]].concat());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let empty = write(dir.path(), "empty.json", r#"{"keyframes":[]}"#);
    let out = occlude(&[&args[..], &["--camera-path", empty.to_str().unwrap()]].concat());
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("empty.json"));
}

#[test]
fn broken_or_unsupported_model_is_a_usage_error_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let broken = write(dir.path(), "broken.gltf", &room_gltf().replace("\"count\":36", "\"count\":3600"));
    let truncated = write(dir.path(), "cut.glb", "glTF\u{2}\0\0\0");
    let unsupported = write(dir.path(), "model.fbx", "");
    let missing = dir.path().join("absent.obj");
    for path in [&broken, &truncated, &unsupported, &missing] {
        let out = occlude(&["bench", "--scene", path.to_str().unwrap(), "--frames", "2", "--resolution", "64x48"]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{}: {stderr}", path.display());
        let name = path.file_name().unwrap().to_str().unwrap();
        assert!(stderr.contains(name), "stderr should name {name}: {stderr}");
    }
}
