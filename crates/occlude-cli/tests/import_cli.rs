//! `occlude bench` on imported model files: a small glTF room runs with every
//! method exact, and a broken model is a usage error (exit code 2) naming it.

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
