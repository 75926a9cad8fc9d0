//! Runs the example renderer off-screen: a walk past the walls, culling off
//! or with an occlude method, printing what each frame drew, and writes the
//! last frame as a PNG.
//!
//! `cargo run --release -p own-renderer -- [--culling off|chcpp|chc|om|sw|vfc]
//! [--frames N] [--grid N] [--size PIXELS] [--reverse-z] [--depth24] [--out FILE.png]`

use own_renderer::{open_device, Options, Renderer};
use std::error::Error;
use std::path::PathBuf;

fn main() {
    if let Err(e) = run() {
        eprintln!("own-renderer: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), Box<dyn Error>> {
    let depth_format = wgpu::TextureFormat::Depth32Float;
    let mut options = Options { size: 512, grid: 60, reverse_z: false, depth_format };
    let (mut culling, mut frames, mut out) = (String::from("chcpp"), 8u32, PathBuf::from("own-renderer.png"));
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        let mut value = || args.next().ok_or_else(|| format!("{arg} needs a value"));
        match arg.as_str() {
            "--culling" => culling = value()?,
            "--frames" => frames = value()?.parse()?,
            "--grid" => options.grid = value()?.parse()?,
            "--size" => options.size = value()?.parse()?,
            "--out" => out = value()?.into(),
            "--reverse-z" => options.reverse_z = true,
            "--depth24" => options.depth_format = wgpu::TextureFormat::Depth24Plus,
            _ => return Err(format!("unknown argument '{arg}' (see the README)").into()),
        }
    }
    if frames == 0 || options.size == 0 || options.grid == 0 {
        return Err("--frames, --size and --grid must be at least 1".into());
    }
    let (device, queue) = open_device()?;
    let mut renderer = Renderer::new(device, queue, options);
    renderer.set_culling((culling != "off").then_some(culling.as_str()))?;
    for frame in 0..frames {
        let t = if frames > 1 { frame as f32 / (frames - 1) as f32 } else { 0.0 };
        let drawn = renderer.render(t)?;
        println!("frame {frame}: culling {culling}, drew {drawn} of {} instances", renderer.instance_count());
    }
    renderer.save_png(&out)?;
    println!("wrote {}", out.display());
    Ok(())
}
