//! Fuzzes the glTF importer: the input as a GLB file and as a glTF JSON file.
//! Any input may be refused with an error; none may panic, hang or give a
//! scene that is not valid (see `common::check`).

#![no_main]

#[path = "common.rs"]
mod common;

use occlude_scenes::import::ModelFormat;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    common::check(data, "fuzz.glb", ModelFormat::Glb);
    common::check(data, "fuzz.gltf", ModelFormat::Gltf);
});
