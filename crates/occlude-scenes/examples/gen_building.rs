//! Writes the generated building of `occlude_scenes::building` as a GLB file,
//! the imported model with real occlusion of docs/benchmarks.md:
//!
//! ```sh
//! cargo run --release -p occlude-scenes --example gen_building -- building.glb [FLOORS] [ROOMS] [SEED]
//! ```
//!
//! FLOORS (default 3) storeys of ROOMS x ROOMS (default 6) rooms, from SEED
//! (default 1).

use occlude_scenes::{building, export};
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let number = |k: usize, default: u32| args.get(k).map_or(Some(default), |a| a.parse::<u32>().ok());
    let positive = |k: usize, default: u32| number(k, default).filter(|&n| n > 0);
    let (Some(out), Some(floors), Some(rooms), Some(seed)) =
        (args.first(), positive(1, 3), positive(2, 6), number(3, 1))
    else {
        eprintln!("usage: gen_building OUT.glb [FLOORS] [ROOMS] [SEED] (FLOORS and ROOMS at least 1)");
        return ExitCode::from(2);
    };
    let scene = building::generate(floors, rooms, seed.into());
    if let Err(e) = std::fs::write(out, export::glb(&scene)) {
        eprintln!("cannot write {out}: {e}");
        return ExitCode::FAILURE;
    }
    println!(
        "{out}: {floors} floors of {rooms} x {rooms} rooms, {} meshes, {} instances, {} triangles",
        scene.meshes.len(),
        scene.instances.len(),
        scene.triangle_count()
    );
    ExitCode::SUCCESS
}
