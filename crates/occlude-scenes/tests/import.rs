//! Importing glTF and OBJ models that the tests write themselves: counts,
//! world transforms, instancing, materials, splitting, automatic paths, and a
//! clear error naming the file for every kind of bad input.

use base64::Engine;
use glam::Vec3;
use occlude_core::Aabb;
use occlude_scenes::import::{import, import_bytes, Imported, ModelFormat};
use occlude_scenes::{building, export};
use occlude_scenes::{load, AutoPath, ImportOptions, LoadError, Size};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// Builds a glTF document and its one binary buffer.
#[derive(Default)]
struct Gltf {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
    meshes: Vec<Value>,
    nodes: Vec<Value>,
    roots: Vec<usize>,
    materials: usize,
}

/// Corners of the cube `[-0.5, 0.5]³` and its 12 triangles.
const CUBE_POSITIONS: [[f32; 3]; 8] = [
    [-0.5, -0.5, -0.5],
    [0.5, -0.5, -0.5],
    [0.5, 0.5, -0.5],
    [-0.5, 0.5, -0.5],
    [-0.5, -0.5, 0.5],
    [0.5, -0.5, 0.5],
    [0.5, 0.5, 0.5],
    [-0.5, 0.5, 0.5],
];
const CUBE_INDICES: [u16; 36] =
    [0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4, 3, 7, 6, 3, 6, 2, 0, 4, 7, 0, 7, 3, 1, 2, 6, 1, 6, 5];

impl Gltf {
    /// Appends `bytes` as a buffer view (4-byte aligned) and returns its index.
    fn view(&mut self, bytes: &[u8]) -> usize {
        self.bin.resize(self.bin.len().next_multiple_of(4), 0);
        self.views.push(json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()}));
        self.bin.extend_from_slice(bytes);
        self.views.len() - 1
    }

    /// Adds an accessor and returns its index.
    fn accessor(&mut self, accessor: Value) -> usize {
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    /// A float VEC3 accessor over `positions`.
    fn positions(&mut self, positions: &[[f32; 3]]) -> usize {
        let bytes: Vec<u8> = positions.iter().flatten().flat_map(|f| f.to_le_bytes()).collect();
        let view = self.view(&bytes);
        // glTF requires the bounds of positions; non-finite values (for the
        // bad-input tests) are left out, as JSON cannot hold them.
        let finite = positions.iter().map(|&p| Vec3::from(p)).filter(|p| p.is_finite());
        let (min, max) = finite.fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| (lo.min(p), hi.max(p)));
        self.accessor(json!({"bufferView": view, "componentType": 5126, "count": positions.len(), "type": "VEC3",
                             "min": min.to_array(), "max": max.to_array()}))
    }

    /// An unsigned-short SCALAR accessor over `indices`.
    fn indices(&mut self, indices: &[u16]) -> usize {
        let bytes: Vec<u8> = indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        let view = self.view(&bytes);
        self.accessor(json!({"bufferView": view, "componentType": 5123, "count": indices.len(), "type": "SCALAR"}))
    }

    /// A mesh of `primitives`; returns its index.
    fn mesh(&mut self, primitives: Vec<Value>) -> usize {
        self.meshes.push(json!({ "primitives": primitives }));
        self.meshes.len() - 1
    }

    /// A triangle primitive over new accessors, with an optional material.
    fn primitive(&mut self, positions: &[[f32; 3]], indices: &[u16], material: Option<usize>) -> Value {
        let (p, i) = (self.positions(positions), self.indices(indices));
        self.materials = self.materials.max(material.map_or(0, |m| m + 1));
        let mut primitive = json!({"attributes": {"POSITION": p}, "indices": i});
        if let Some(m) = material {
            primitive["material"] = json!(m);
        }
        primitive
    }

    /// The cube as a one-primitive mesh.
    fn cube(&mut self, material: Option<usize>) -> usize {
        let primitive = self.primitive(&CUBE_POSITIONS, &CUBE_INDICES, material);
        self.mesh(vec![primitive])
    }

    /// Adds a node and returns its index.
    fn node(&mut self, node: Value) -> usize {
        self.nodes.push(node);
        self.nodes.len() - 1
    }

    /// Adds a root node of the scene.
    fn root(&mut self, node: Value) -> usize {
        let n = self.node(node);
        self.roots.push(n);
        n
    }

    /// The document, its buffer at `uri` (none: the GLB binary chunk).
    fn document(&self, uri: Option<String>) -> Value {
        let mut buffer = json!({"byteLength": self.bin.len()});
        if let Some(uri) = uri {
            buffer["uri"] = json!(uri);
        }
        let materials: Vec<Value> = (0..self.materials).map(|m| json!({ "name": format!("m{m}") })).collect();
        json!({
            "asset": {"version": "2.0"},
            "scene": 0,
            "scenes": [{"nodes": self.roots}],
            "nodes": self.nodes,
            "meshes": self.meshes,
            "materials": materials,
            "accessors": self.accessors,
            "bufferViews": self.views,
            "buffers": [buffer],
        })
    }

    /// Writes `dir/name` with the buffer as a base64 data URI.
    fn write(&self, dir: &Path, name: &str) -> PathBuf {
        let data = base64::engine::general_purpose::STANDARD.encode(&self.bin);
        write_json(dir, name, &self.document(Some(format!("data:application/octet-stream;base64,{data}"))))
    }

    /// Writes `dir/name` with the buffer in the file `dir/file`, which the
    /// document names by `uri`.
    fn write_with_bin(&self, dir: &Path, name: &str, file: &str, uri: &str) -> PathBuf {
        std::fs::write(dir.join(file), &self.bin).unwrap();
        write_json(dir, name, &self.document(Some(uri.to_string())))
    }

    /// The model as GLB bytes.
    fn glb(&self) -> Vec<u8> {
        export::container(&serde_json::to_vec(&self.document(None)).unwrap(), &self.bin)
    }

    /// Overrides elements of accessor `accessor` by a sparse substitution:
    /// `count` substitutions, the unsigned-byte `indices` and the bytes
    /// `values` in buffer views of their own.
    fn sparse(&mut self, accessor: usize, count: usize, indices: &[u8], values: &[u8]) {
        let (i, v) = (self.view(indices), self.view(values));
        self.accessors[accessor]["sparse"] = json!({
            "count": count,
            "indices": {"bufferView": i, "componentType": 5121},
            "values": {"bufferView": v},
        });
    }
}

fn write_json(dir: &Path, name: &str, document: &Value) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, serde_json::to_vec_pretty(document).unwrap()).unwrap();
    path
}

fn write(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

/// A node placing a mesh scaled to and moved onto `min..max`.
fn placed(mesh: usize, min: [f32; 3], max: [f32; 3]) -> Value {
    let (min, max) = (Vec3::from(min), Vec3::from(max));
    json!({"mesh": mesh, "translation": ((min + max) / 2.0).to_array(), "scale": (max - min).to_array()})
}

/// A 10 x 3 x 10 m room: a floor (no material), four walls (material 0) and
/// three boxes (material 1). Three meshes, eight instances.
fn room() -> Gltf {
    let mut g = Gltf::default();
    let (floor, wall, crate_) = (g.cube(None), g.cube(Some(0)), g.cube(Some(1)));
    g.root(placed(floor, [0.0, -0.1, 0.0], [10.0, 0.0, 10.0]));
    g.root(placed(wall, [0.0, 0.0, 0.0], [0.2, 3.0, 10.0]));
    g.root(placed(wall, [9.8, 0.0, 0.0], [10.0, 3.0, 10.0]));
    g.root(placed(wall, [0.0, 0.0, 0.0], [10.0, 3.0, 0.2]));
    g.root(placed(wall, [0.0, 0.0, 9.8], [10.0, 3.0, 10.0]));
    for x in [2.0, 5.0, 8.0] {
        g.root(placed(crate_, [x - 0.5, 0.0, 4.5], [x + 0.5, 1.0, 5.5]));
    }
    g
}

fn options(split_triangles: usize, auto_path: AutoPath) -> ImportOptions {
    ImportOptions { split_triangles, auto_path }
}

fn import_file(path: &Path, options: ImportOptions) -> Imported {
    let format = match path.extension().unwrap().to_str().unwrap() {
        "gltf" => ModelFormat::Gltf,
        "glb" => ModelFormat::Glb,
        _ => ModelFormat::Obj,
    };
    import(path, format, &options).unwrap_or_else(|e| panic!("{} should import: {e}", path.display()))
}

fn assert_close(a: Aabb, b: Aabb) {
    assert!((a.min - b.min).abs().max_element() < 1e-5 && (a.max - b.max).abs().max_element() < 1e-5, "{a:?} != {b:?}");
}

fn room_bounds() -> Aabb {
    Aabb::new(Vec3::new(0.0, -0.1, 0.0), Vec3::new(10.0, 3.0, 10.0))
}

#[test]
fn room_of_boxes_gives_its_meshes_instances_materials_and_bounds() {
    let dir = tempfile::tempdir().unwrap();
    let path = room().write(dir.path(), "room.gltf");
    let scene = load(path.to_str().unwrap(), Size::Small, 1, &ImportOptions::default()).unwrap();
    assert_eq!(scene.name, "room.gltf");
    assert_eq!(scene.meshes.len(), 3);
    assert_eq!(scene.instances.len(), 8);
    assert_eq!(scene.triangle_count(), 8 * 12);
    assert_eq!(scene.material_count, 3, "two glTF materials and the default one");
    let materials: Vec<u32> = scene.instances.iter().map(|i| i.material).collect();
    assert_eq!(materials, [2, 0, 0, 0, 0, 1, 1, 1]);
    assert_close(scene.bounds(), room_bounds());
    assert!(!scene.path.keyframes.is_empty());
}

#[test]
fn glb_and_external_buffer_give_the_same_scene_as_a_data_uri() {
    let dir = tempfile::tempdir().unwrap();
    let model = room();
    let reference = import_file(&model.write(dir.path(), "a.gltf"), ImportOptions::default()).scene;
    for path in [model.write_with_bin(dir.path(), "b.gltf", "b.bin", "b.bin"), write(dir.path(), "c.glb", model.glb())]
    {
        let scene = import_file(&path, ImportOptions::default()).scene;
        assert_eq!(scene.instances.len(), reference.instances.len());
        assert_eq!(scene.triangle_count(), reference.triangle_count());
        assert_eq!(scene.bounds(), reference.bounds());
        assert_eq!(scene.path, reference.path);
    }
}

#[test]
fn nested_nodes_compose_their_transforms() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::default();
    let cube = g.cube(None);
    // Grandchild: a matrix moving by (0, 0, 3); child: up 1 with the cube;
    // parent: at x = 10, scaled 2.
    let grandchild = g.node(json!({"mesh": cube, "matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,3,1]}));
    let child = g.node(json!({"mesh": cube, "translation": [0, 1, 0], "children": [grandchild]}));
    g.root(json!({"translation": [10, 0, 0], "scale": [2, 2, 2], "children": [child]}));
    let scene = import_file(&g.write(dir.path(), "nested.gltf"), ImportOptions::default()).scene;
    assert_eq!(scene.instances.len(), 2);
    assert_close(scene.instances[0].bounds, Aabb::new(Vec3::new(9.0, 1.0, -1.0), Vec3::new(11.0, 3.0, 1.0)));
    assert_close(scene.instances[1].bounds, Aabb::new(Vec3::new(9.0, 1.0, 5.0), Vec3::new(11.0, 3.0, 7.0)));
}

#[test]
fn a_mesh_used_by_several_nodes_is_instanced() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::default();
    let cube = g.cube(Some(0));
    for x in 0..5 {
        g.root(json!({"mesh": cube, "translation": [x as f32 * 2.0, 0, 0]}));
    }
    let scene = import_file(&g.write(dir.path(), "row.gltf"), ImportOptions::default()).scene;
    assert_eq!(scene.meshes.len(), 1);
    assert_eq!(scene.instances.len(), 5);
    assert_eq!(scene.unique_triangle_count(), 12);
    assert_eq!(scene.triangle_count(), 60);
    assert_close(scene.bounds(), Aabb::new(Vec3::splat(-0.5), Vec3::new(8.5, 0.5, 0.5)));
}

#[test]
fn strips_become_triangles_and_lines_are_skipped_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::default();
    let quad = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
    let mut strip = g.primitive(&quad, &[0, 1, 2, 3], None);
    strip["mode"] = json!(5);
    let mut lines = g.primitive(&quad, &[0, 1, 2, 3], None);
    lines["mode"] = json!(1);
    let mesh = g.mesh(vec![strip, lines]);
    g.root(json!({ "mesh": mesh }));
    let imported = import_file(&g.write(dir.path(), "modes.gltf"), ImportOptions::default());
    assert_eq!(imported.scene.triangle_count(), 2);
    assert_eq!(imported.scene.meshes[0].indices, [0, 1, 2, 2, 1, 3]);
    assert_eq!(imported.warnings.len(), 1);
    assert!(imported.warnings[0].contains("modes.gltf") && imported.warnings[0].contains("primitive 1"));
}

#[test]
fn large_meshes_are_split_into_several_instanced_meshes() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::default();
    let cube = g.cube(None);
    g.root(json!({ "mesh": cube }));
    g.root(json!({"mesh": cube, "translation": [3, 0, 0]}));
    let path = g.write(dir.path(), "split.gltf");
    let whole = import_file(&path, options(0, AutoPath::Orbit)).scene;
    assert_eq!((whole.meshes.len(), whole.instances.len()), (1, 2));
    let split = import_file(&path, options(4, AutoPath::Orbit)).scene;
    assert_eq!(split.meshes.len(), 4, "12 triangles split down to at most 4");
    assert_eq!(split.instances.len(), 8, "every placement of the mesh places every part");
    assert!(split.meshes.iter().all(|m| m.triangle_count() <= 4));
    assert_eq!(split.triangle_count(), whole.triangle_count());
    assert_eq!(split.bounds(), whole.bounds());
}

#[test]
fn walk_path_stays_at_eye_height_clear_of_the_room() {
    let dir = tempfile::tempdir().unwrap();
    let imported = import_file(&room().write(dir.path(), "room.gltf"), options(0, AutoPath::Walk));
    assert!(imported.warnings.is_empty(), "{:?}", imported.warnings);
    let scene = &imported.scene;
    for k in &scene.path.keyframes {
        assert!((k.position.y - (-0.1 + 1.7)).abs() < 1e-4);
        let eye = Aabb::new(k.position - Vec3::splat(0.24), k.position + Vec3::splat(0.24));
        assert!(scene.instances.iter().all(|i| !i.bounds.overlaps(&eye)), "{:?} touches an object", k.position);
        assert!(room_bounds().contains_point(k.position), "the walk stays inside the room");
    }
}

#[test]
fn walk_falls_back_to_orbit_with_a_warning_when_there_is_no_free_space() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::default();
    let cube = g.cube(None);
    g.root(json!({"mesh": cube, "scale": [10, 10, 10]}));
    let path = g.write(dir.path(), "block.gltf");
    let walked = import_file(&path, options(0, AutoPath::Walk));
    assert_eq!(walked.warnings.len(), 1);
    assert!(walked.warnings[0].contains("block.gltf") && walked.warnings[0].contains("orbit"));
    assert_eq!(walked.scene.path, import_file(&path, options(0, AutoPath::Orbit)).scene.path);
    for k in &walked.scene.path.keyframes {
        assert!(!walked.scene.bounds().contains_point(k.position));
    }
}

#[test]
fn obj_objects_materials_and_relative_indices() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "two.mtl", "newmtl red\nKd 1 0 0\nnewmtl blue\nKd 0 0 1\n");
    let obj = "mtllib two.mtl\n\
        v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
        o red_quad\nusemtl red\nf 1 2 3 4\n\
        v 0 0 2\nv 1 0 2\nv 1 1 2\n\
        o blue_tri\nusemtl blue\nf -3 -2 -1\n\
        o plain\nusemtl none\nf 1 2 5\n";
    let imported = import_file(&write(dir.path(), "shapes.obj", obj), ImportOptions::default());
    assert!(imported.warnings.is_empty(), "{:?}", imported.warnings);
    let scene = imported.scene;
    assert_eq!(scene.instances.len(), 3);
    assert_eq!(scene.triangle_count(), 4, "the quad is triangulated");
    let materials: Vec<u32> = scene.instances.iter().map(|i| i.material).collect();
    assert_eq!(materials, [0, 1, 2]);
    assert_eq!(scene.material_count, 3);
    assert_close(scene.instances[1].bounds, Aabb::new(Vec3::new(0.0, 0.0, 2.0), Vec3::new(1.0, 1.0, 2.0)));
}

#[test]
fn obj_without_its_mtl_warns_and_uses_one_material() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "lost.obj", "mtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n");
    let imported = import_file(&path, ImportOptions::default());
    assert_eq!(imported.warnings.len(), 1);
    assert!(imported.warnings[0].contains("lost.obj"));
    assert_eq!(imported.scene.material_count, 1);
}

#[test]
fn procedural_names_still_generate() {
    let scene = load("city", Size::Small, 1, &ImportOptions::default()).unwrap();
    assert_eq!(scene.name, "city");
}

/// The error of loading `path`, checked to name the file.
fn error(path: &Path) -> (LoadError, String) {
    let e = load(path.to_str().unwrap(), Size::Small, 1, &ImportOptions::default()).expect_err("bad input");
    let message = e.to_string();
    let name = path.file_name().unwrap().to_str().unwrap();
    assert!(message.contains(name), "the error should name {name}: {message}");
    (e, message)
}

#[test]
fn truncated_glb_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let glb = room().glb();
    let (e, message) = error(&write(dir.path(), "cut.glb", &glb[..glb.len() / 2]));
    assert!(matches!(e, LoadError::Malformed { format: "GLB", .. }), "{e:?}");
    assert!(message.contains("truncated"), "{message}");
    let (_, message) = error(&write(dir.path(), "stub.glb", &glb[..7]));
    assert!(message.contains("12-byte GLB header"), "{message}");
}

#[test]
fn glb_header_claiming_2_gb_is_an_error_without_allocating_it() {
    let dir = tempfile::tempdir().unwrap();
    let mut glb = room().glb();
    glb[8..12].copy_from_slice(&2_000_000_000u32.to_le_bytes());
    let (_, message) = error(&write(dir.path(), "huge.glb", &glb));
    assert!(message.contains("2000000000"), "{message}");
    // The same claim on a chunk: the file length is right, the chunk's is not.
    let mut glb = room().glb();
    glb[12..16].copy_from_slice(&2_000_000_000u32.to_le_bytes());
    let (_, message) = error(&write(dir.path(), "huge_chunk.glb", &glb));
    assert!(message.contains("claims 2000000000 bytes"), "{message}");
}

#[test]
fn gltf_with_a_missing_buffer_file_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = room().write_with_bin(dir.path(), "room.gltf", "room.bin", "room.bin");
    std::fs::remove_file(dir.path().join("room.bin")).unwrap();
    let (e, message) = error(&path);
    assert!(matches!(e, LoadError::MissingFile { .. }), "{e:?}");
    assert!(message.contains("room.bin"), "{message}");
}

#[test]
fn index_out_of_range_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::default();
    let primitive = g.primitive(&CUBE_POSITIONS, &[0, 1, 8], None);
    let mesh = g.mesh(vec![primitive]);
    g.root(json!({ "mesh": mesh }));
    let (e, message) = error(&g.write(dir.path(), "index.gltf"));
    assert!(matches!(e, LoadError::Invalid { .. }), "{e:?}");
    assert!(message.contains("index 8 is out of range"), "{message}");
}

#[test]
fn accessor_past_its_buffer_view_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = room();
    g.accessors[0]["count"] = json!(1_000_000);
    let (_, message) = error(&g.write(dir.path(), "overrun.gltf"));
    assert!(message.contains("accessor 0 reads 1000000 elements"), "{message}");
}

#[test]
fn nan_or_infinite_positions_are_an_error() {
    let dir = tempfile::tempdir().unwrap();
    for (name, bad) in [("nan.gltf", f32::NAN), ("inf.gltf", f32::INFINITY)] {
        let mut g = Gltf::default();
        let primitive = g.primitive(&[[0.0; 3], [1.0, 0.0, 0.0], [0.0, bad, 0.0]], &[0, 1, 2], None);
        let mesh = g.mesh(vec![primitive]);
        g.root(json!({ "mesh": mesh }));
        let (_, message) = error(&g.write(dir.path(), name));
        assert!(message.contains("vertex 2 has a non-finite position"), "{message}");
    }
    let (_, message) = error(&write(dir.path(), "inf.obj", "v 0 0 0\nv 1 0 0\nv 0 inf 0\nf 1 2 3\n"));
    assert!(message.contains("non-finite"), "{message}");
}

#[test]
fn empty_scene_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let (e, _) = error(&Gltf::default().write(dir.path(), "empty.gltf"));
    assert!(matches!(e, LoadError::Empty { .. }), "{e:?}");
    let (e, _) = error(&write(dir.path(), "empty.obj", "# nothing\nv 0 0 0\n"));
    assert!(matches!(e, LoadError::Empty { .. }), "{e:?}");
}

#[test]
fn node_cycle_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::default();
    let cube = g.cube(None);
    g.root(json!({"mesh": cube, "children": [1]}));
    g.node(json!({"mesh": cube, "children": [0]}));
    let (_, message) = error(&g.write(dir.path(), "cycle.gltf"));
    assert!(message.contains("not a tree"), "{message}");
}

#[test]
fn invalid_json_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let (e, _) = error(&write(dir.path(), "broken.gltf", "{\"asset\": "));
    assert!(matches!(e, LoadError::Malformed { format: "glTF", .. }), "{e:?}");
}

/// Every OBJ index must name an element of the file, and is checked before
/// `tobj` reads it: indices that would wrap its offset arithmetic (and
/// panic inside it) are an error naming the line like any other.
#[test]
fn obj_indices_out_of_range_are_an_error_but_relative_ones_are_legal() {
    let dir = tempfile::tempdir().unwrap();
    let vertices = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvt 0 0\n";
    let ok = import_file(&write(dir.path(), "relative.obj", format!("{vertices}f -3 -2 -1\n")), Default::default());
    assert_eq!(ok.scene.triangle_count(), 1);
    for (name, face) in [
        ("minus.obj", "f -1 -2 -9"),
        ("past.obj", "f 1 2 7"),
        ("zero.obj", "f 0 1 2"),
        ("wrap.obj", "f 1//6148914691236517206 2//1 3//1"),
        ("texture.obj", "f 1/9223372036854775807 2/1 3/1"),
        ("behind.obj", "f 1//-3 2//1 3//1"),
    ] {
        let (e, message) = error(&write(dir.path(), name, format!("{vertices}{face}\n")));
        assert!(matches!(e, LoadError::Malformed { format: "OBJ", .. }), "{e:?}");
        assert!(message.contains("line 6") && message.contains("out of range"), "{message}");
    }
}

#[test]
fn unknown_names_and_missing_files_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let (e, message) = error(&write(dir.path(), "model.fbx", "x"));
    assert!(matches!(e, LoadError::UnknownScene { .. }), "{e:?}");
    assert!(message.contains("teapots") && message.contains(".glb") && message.contains(".obj"), "{message}");
    let (e, _) = error(&dir.path().join("absent.glb"));
    assert!(matches!(e, LoadError::Io { .. }), "{e:?}");
}

#[test]
fn percent_encoded_buffer_uris_name_their_files() {
    let dir = tempfile::tempdir().unwrap();
    let model = room();
    let reference = import_file(&model.write(dir.path(), "a.gltf"), ImportOptions::default()).scene;
    for (name, file, uri) in [
        ("spaced.gltf", "my buffer (1).bin", "my%20buffer%20%281%29.bin"),
        ("umlaut.gltf", "bär.bin", "b%C3%a4r.bin"),
        ("plain.gltf", "50%.bin", "50%25.bin"),
    ] {
        let scene = import_file(&model.write_with_bin(dir.path(), name, file, uri), ImportOptions::default()).scene;
        assert_eq!(scene.triangle_count(), reference.triangle_count(), "{uri}");
        assert_eq!(scene.bounds(), reference.bounds(), "{uri}");
    }
    // Escapes are decoded, not taken literally: the file of that literal name is not read.
    std::fs::write(dir.path().join("x%41.bin"), &model.bin).unwrap();
    let (e, message) = error(&model.write_with_bin(dir.path(), "literal.gltf", "x%41.bin", "x%41.bin"));
    assert!(matches!(e, LoadError::MissingFile { .. }), "{e:?}");
    assert!(message.contains("xA.bin"), "{message}");
}

#[test]
fn bad_percent_escapes_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let model = room();
    for (name, uri, escape) in [
        ("zz.gltf", "my%zzbuffer.bin", "'%zz' at byte 2"),
        ("end.gltf", "buffer.bin%", "'%' at byte 10"),
        ("short.gltf", "buffer.bin%4", "'%4' at byte 10"),
        ("sign.gltf", "%+1buffer.bin", "'%+1' at byte 0"),
    ] {
        let (e, message) = error(&model.write_with_bin(dir.path(), name, "buffer.bin", uri));
        assert!(matches!(e, LoadError::Invalid { .. }), "{e:?}");
        assert!(message.contains(&format!("buffer 0: its URI '{uri}' has a bad percent escape {escape}")), "{message}");
    }
    let (_, message) = error(&model.write_with_bin(dir.path(), "latin1.gltf", "buffer.bin", "b%E4r.bin"));
    assert!(message.contains("'b%E4r.bin' decodes to bytes that are not UTF-8"), "{message}");
}

/// Writes `g` as `dir/name` with one mesh at the root drawing its accessor 0
/// as positions (no indices).
fn write_over_accessor_0(mut g: Gltf, dir: &Path, name: &str) -> PathBuf {
    let mesh = g.mesh(vec![json!({"attributes": {"POSITION": 0}})]);
    g.root(json!({ "mesh": mesh }));
    g.write(dir, name)
}

/// The positions of the one mesh of [`write_over_accessor_0`], imported.
fn positions_of_accessor_0(g: Gltf, dir: &Path, name: &str) -> Vec<Vec3> {
    let scene = import_file(&write_over_accessor_0(g, dir, name), options(0, AutoPath::Orbit)).scene;
    assert_eq!(scene.meshes.len(), 1);
    scene.meshes[0].positions.clone()
}

fn floats(values: &[[f32; 3]]) -> Vec<u8> {
    values.iter().flatten().flat_map(|f| f.to_le_bytes()).collect()
}

#[test]
fn sparse_accessors_override_their_base_or_zeros() {
    let dir = tempfile::tempdir().unwrap();
    // On a base from a buffer view: vertices 1 and 4 of six move.
    let mut g = Gltf::default();
    let base: Vec<[f32; 3]> = (0..6).map(|k| [k as f32, 0.0, 0.0]).collect();
    g.positions(&base);
    g.sparse(0, 2, &[1, 4], &floats(&[[1.0, 5.0, 0.0], [4.0, 0.0, 7.0]]));
    let mut expected: Vec<Vec3> = base.iter().map(|&p| Vec3::from(p)).collect();
    expected[1] = Vec3::new(1.0, 5.0, 0.0);
    expected[4] = Vec3::new(4.0, 0.0, 7.0);
    assert_eq!(positions_of_accessor_0(g, dir.path(), "on_view.gltf"), expected);

    // On zeros: an accessor without a buffer view.
    let mut g = Gltf::default();
    g.accessor(json!({"componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}));
    g.sparse(0, 2, &[1, 2], &floats(&[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]));
    assert_eq!(positions_of_accessor_0(g, dir.path(), "on_zeros.gltf"), [Vec3::ZERO, Vec3::X, Vec3::Y]);

    // On indices: the same substitution for every element type.
    let mut g = Gltf::default();
    let quad = g.positions(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]]);
    let indices = g.indices(&[0, 1, 2, 0, 1, 2]);
    g.sparse(indices, 2, &[4, 5], &[3, 0, 2, 0]);
    let mesh = g.mesh(vec![json!({"attributes": {"POSITION": quad}, "indices": indices})]);
    g.root(json!({ "mesh": mesh }));
    let scene = import_file(&g.write(dir.path(), "indices.gltf"), options(0, AutoPath::Orbit)).scene;
    assert_eq!(scene.meshes[0].indices, [0, 1, 2, 0, 3, 2]);
}

#[test]
fn malformed_sparse_accessors_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let cube = || {
        let mut g = Gltf::default();
        g.positions(&CUBE_POSITIONS);
        g
    };
    let two = floats(&[[0.0; 3], [1.0; 3]]);
    let without_view = |g: &mut Gltf| {
        g.accessors[0].as_object_mut().unwrap().remove("bufferView");
        g.accessors[0]["count"] = json!(3_000_000_000u64);
        g.sparse(0, 2, &[1, 2], &two);
    };
    type Damage<'a> = Box<dyn Fn(&mut Gltf) + 'a>;
    let cases: [(&str, Damage, &str); 6] = [
        (
            "range.gltf",
            Box::new(|g| g.sparse(0, 2, &[1, 8], &two)),
            "accessor 0: sparse index 8 (substitution 1) is out of range: the accessor has 8 elements",
        ),
        (
            "count.gltf",
            Box::new(|g| g.sparse(0, 9, &[0; 9], &floats(&[[0.0; 3]; 9]))),
            "accessor 0 has a sparse count of 9, more than its 8 elements",
        ),
        (
            "order.gltf",
            Box::new(|g| g.sparse(0, 2, &[3, 3], &two)),
            "accessor 0: sparse index 3 (substitution 1) does not increase",
        ),
        (
            "indices.gltf",
            Box::new(|g| g.sparse(0, 3, &[1, 2], &floats(&[[0.0; 3]; 3]))),
            "accessor 0: its sparse indices reads 3 elements of 1 bytes from byte 0 but buffer view 1 has only 2",
        ),
        (
            "values.gltf",
            Box::new(|g| g.sparse(0, 2, &[1, 2], &two[..20])),
            "accessor 0: its sparse values reads 2 elements of 12 bytes from byte 0 but buffer view 2 has only 20",
        ),
        ("zeros.gltf", Box::new(without_view), "accessor 0 has no buffer view and claims 3000000000 elements of zeros"),
    ];
    for (name, damage, problem) in cases {
        let mut g = cube();
        damage(&mut g);
        let (e, message) = error(&write_over_accessor_0(g, dir.path(), name));
        assert!(matches!(e, LoadError::Invalid { .. }), "{name}: {e:?}");
        assert!(message.contains(problem), "{name}: {message}");
    }
}

#[test]
fn exported_scenes_import_as_they_were() {
    for scene in [occlude_scenes::generate("city", Size::Small, 1).unwrap(), building::generate(2, 2, 7)] {
        let glb = export::glb(&scene);
        let imported = import_bytes(Path::new("export.glb"), &glb, ModelFormat::Glb, &options(0, AutoPath::Orbit));
        let back = imported.unwrap_or_else(|e| panic!("{}: {e}", scene.name)).scene;
        assert_eq!(back.instances.len(), scene.instances.len(), "{}", scene.name);
        assert_eq!(back.material_count, scene.material_count, "{}", scene.name);
        assert_eq!(back.triangle_count(), scene.triangle_count(), "{}", scene.name);
        for (a, b) in scene.instances.iter().zip(&back.instances) {
            assert_eq!((a.transform, a.material, a.bounds), (b.transform, b.material, b.bounds), "{}", scene.name);
            let (ma, mb) = (&scene.meshes[a.mesh as usize], &back.meshes[b.mesh as usize]);
            assert_eq!((&ma.positions, &ma.indices), (&mb.positions, &mb.indices), "{}", scene.name);
        }
    }
}

#[test]
fn generated_building_is_walked_from_room_to_room_on_its_ground_floor() {
    let scene = building::generate(2, 3, 1);
    assert!(scene.instances.len() > 100 && scene.triangle_count() > 30_000, "{} instances", scene.instances.len());
    let path = Path::new("building.glb");
    let imported = import_bytes(path, &export::glb(&scene), ModelFormat::Glb, &options(0, AutoPath::Walk)).unwrap();
    assert!(imported.warnings.is_empty(), "{:?}", imported.warnings);
    let keys = &imported.scene.path.keyframes;
    let visited = Aabb::from_points(keys.iter().map(|k| &k.position));
    assert!(visited.extent().max_element() > 6.0, "the walk leaves the first 5 m room: {visited:?}");
    assert!(keys.iter().all(|k| (k.position.y - (1.7 - 0.2)).abs() < 1e-4), "eye height over the ground slab");
}

/// Found by fuzzing: the `gltf` crate's validation panicked on a POSITION
/// accessor index past the accessors.
#[test]
fn position_accessor_that_does_not_exist_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = room();
    g.meshes[0]["primitives"][0]["attributes"]["POSITION"] = json!(99);
    for path in [g.write(dir.path(), "position.gltf"), write(dir.path(), "position.glb", g.glb())] {
        let (e, message) = error(&path);
        assert!(matches!(e, LoadError::Malformed { .. }), "{e:?}");
        assert!(
            message.contains("mesh 0 primitive 0: its POSITION accessor 99 does not exist: there are 6"),
            "{message}"
        );
    }
}

/// Found by fuzzing: positions or transforms of about 1e31 m are finite, but
/// the automatic path around them was not. Placements beyond 1e9 m from the
/// origin are an error naming the node or object; 1e8 m still imports.
#[test]
fn models_reaching_beyond_1e9_metres_are_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let far = |name: &str, node: Value| {
        let mut g = Gltf::default();
        let cube = g.cube(None);
        g.root(json!({ "mesh": cube }));
        let mut node = node;
        node["mesh"] = json!(cube);
        g.root(node);
        g.write(dir.path(), name)
    };
    let near = import_file(&far("near.gltf", json!({"translation": [1e8, 0, 0]})), ImportOptions::default());
    assert!(near.scene.path.keyframes.iter().all(|k| k.position.is_finite()));
    for (name, node) in [
        ("scaled.gltf", json!({"scale": [1e30, 1, 1]})),
        ("moved.gltf", json!({"translation": [0, -2e9, 0]})),
        ("overflow.gltf", json!({"scale": [1e30, 1, 1], "translation": [3e38, 0, 0]})),
    ] {
        let (e, message) = error(&far(name, node));
        assert!(matches!(e, LoadError::Invalid { .. }), "{e:?}");
        assert!(message.contains("node 1: its world box reaches") && message.contains("beyond the 1e9 m"), "{message}");
    }
    let (_, message) = error(&write(dir.path(), "far.obj", "o far\nv 0 0 0\nv 1 0 0\nv 0 4e31 0\nf 1 2 3\n"));
    assert!(message.contains("object 'far': its world box reaches 4e31 m"), "{message}");
}

/// Found by fuzzing: an OBJ object without faces became an instance with an
/// empty (infinite) box. Objects and primitives without triangles are left
/// out.
#[test]
fn objects_without_triangles_are_left_out() {
    let dir = tempfile::tempdir().unwrap();
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\no lines\nl 1 2\no points\np 3\no triangle\nf 1 2 3\n";
    let mut g = Gltf::default();
    let (two, three) = (g.primitive(&CUBE_POSITIONS, &[0, 1], None), g.primitive(&CUBE_POSITIONS, &[0, 1, 2], None));
    let mesh = g.mesh(vec![two, three]);
    g.root(json!({ "mesh": mesh }));
    for path in [write(dir.path(), "lines.obj", obj), g.write(dir.path(), "short.gltf")] {
        let scene = import_file(&path, ImportOptions::default()).scene;
        assert_eq!(scene.instances.len(), 1, "{}", path.display());
        assert_eq!(scene.meshes.len(), 1, "{}", path.display());
        assert!(!scene.instances[0].bounds.is_empty() && scene.instances[0].bounds.is_finite());
    }
}

#[test]
fn interleaved_positions_are_read_with_their_stride_and_offset() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::default();
    let quad = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
    // Each vertex: 4 bytes of something else, then its position; the view
    // ends with the last position.
    let bytes: Vec<u8> = quad.iter().flat_map(|p| [7.0f32, p[0], p[1], p[2]]).flat_map(f32::to_le_bytes).collect();
    let view = g.view(&bytes);
    g.views[view]["byteStride"] = json!(16);
    g.accessor(json!({"bufferView": view, "byteOffset": 4, "componentType": 5126, "count": 4, "type": "VEC3",
                      "min": [0, 0, 0], "max": [1, 1, 0]}));
    let positions = positions_of_accessor_0(g, dir.path(), "interleaved.gltf");
    assert_eq!(positions, quad.map(Vec3::from));
}

/// Accessors without a buffer view are zeros that no byte of the file pays
/// for: together they may have at most 2^22 elements, so a small file cannot
/// make the importer allocate gigabytes.
#[test]
fn zeros_without_bytes_are_capped_per_file() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::default();
    let substitutes = floats(&[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    for _ in 0..2 {
        let zeros =
            json!({"componentType": 5126, "count": 3_000_000, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]});
        let a = g.accessor(zeros);
        g.sparse(a, 2, &[1, 2], &substitutes);
    }
    let triangle = g.indices(&[0, 1, 2]);
    let primitives = (0..2).map(|p| json!({"attributes": {"POSITION": p}, "indices": triangle})).collect();
    let mesh = g.mesh(primitives);
    g.root(json!({ "mesh": mesh }));
    let (e, message) = error(&g.write(dir.path(), "zeros.gltf"));
    assert!(matches!(e, LoadError::Invalid { .. }), "{e:?}");
    let problem = "mesh 0 primitive 1: accessor 1 has no buffer view and claims 3000000 elements of zeros";
    assert!(message.contains(problem) && message.contains("(1194304 left)"), "{message}");
}

/// A model reads only regular files inside its folder, and of a glTF buffer
/// only its declared length: every reference that leaves the folder (by a
/// root, `..`, an escape that decodes to either, a link, a URL) or names a
/// device is refused naming it, and a longer file is cut at `byteLength`.
#[test]
fn referenced_files_are_read_inside_the_models_folder_up_to_their_declared_length() {
    let dir = tempfile::tempdir().unwrap();
    let model = room();
    let reference = import_file(&model.write(dir.path(), "a.gltf"), ImportOptions::default()).scene;
    let mut longer = model.bin.clone();
    longer.extend([0xAB; 4096]);
    std::fs::write(dir.path().join("long.bin"), &longer).unwrap();
    let long = write_json(dir.path(), "long.gltf", &model.document(Some("long.bin".into())));
    assert_eq!(import_file(&long, ImportOptions::default()).scene.bounds(), reference.bounds());
    std::fs::create_dir(dir.path().join("models")).unwrap();
    std::os::unix::fs::symlink("/dev/zero", dir.path().join("models").join("zero.bin")).unwrap();
    for (uri, why) in [
        ("/dev/zero", "leaves the model's folder"),
        ("%2Fdev%2Furandom", "leaves the model's folder"),
        ("../../dev/zero", "leaves the model's folder"),
        ("../long.bin", "leaves the model's folder"),
        ("zero.bin", "link that leaves"),
        ("http://example.com/long.bin", "is a URL"),
    ] {
        let path = write_json(&dir.path().join("models"), "m.gltf", &model.document(Some(uri.into())));
        let (e, message) = error(&path);
        assert!(matches!(e, LoadError::Invalid { .. }), "{uri}: {e:?}");
        assert!(message.contains("buffer 0") && message.contains(why), "{message}");
    }
    std::fs::create_dir(dir.path().join("folder.bin")).unwrap();
    let (e, message) = error(&write_json(dir.path(), "dir.gltf", &model.document(Some("folder.bin".into()))));
    assert!(matches!(e, LoadError::MissingFile { .. }) && message.contains("not a regular file"), "{message}");

    let triangle = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    for (mtl, why) in [("/dev/zero", "leaves the model's folder"), ("../x.mtl", "leaves"), ("folder.bin", "regular")] {
        let obj = write(dir.path(), "m.obj", format!("mtllib {mtl}\n{triangle}"));
        let imported = import_file(&obj, ImportOptions::default());
        assert_eq!(imported.scene.triangle_count(), 1);
        assert!(imported.warnings.iter().any(|w| w.contains(mtl) && w.contains(why)), "{:?}", imported.warnings);
    }
}

/// Without a scene, every node is a root or below one: nodes that are each
/// other's children (a cycle no root reaches) are an error, with or without
/// another root beside them.
#[test]
fn a_node_cycle_without_a_scene_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    for extra_root in [false, true] {
        let mut g = Gltf::default();
        let cube = g.cube(None);
        g.node(json!({"mesh": cube, "children": [1]}));
        g.node(json!({"mesh": cube, "children": [0]}));
        if extra_root {
            g.node(json!({ "mesh": cube }));
        }
        let mut document = g.document(Some(format!(
            "data:application/octet-stream;base64,{}",
            base64::engine::general_purpose::STANDARD.encode(&g.bin)
        )));
        let object = document.as_object_mut().unwrap();
        object.remove("scene");
        object.remove("scenes");
        let (_, message) = error(&write_json(dir.path(), "cycle.gltf", &document));
        assert!(message.contains("node 0 is in a cycle") && message.contains("not a tree"), "{message}");
    }
}
