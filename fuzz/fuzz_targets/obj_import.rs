//! Fuzzes the OBJ importer. Any input may be refused with an error; none may
//! panic, hang or give a scene that is not valid (see `common::check`).

#![no_main]

#[path = "common.rs"]
mod common;

use occlude_scenes::import::ModelFormat;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    common::check(data, "fuzz.obj", ModelFormat::Obj);
});
