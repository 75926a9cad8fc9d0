//! A profiling harness for the masked buffer: a fixed number of calls of the
//! fill-rate workload (`occlude_soft::workload::right_triangles`, two screens of
//! pixels per call, back to front, 1920x1080), so that an instruction counter
//! (`scripts/raster-icount.sh`, valgrind) or a profiler sees the same work on
//! every run. Takes the flags of `occlude-soft`'s `fill_calls` example and prints
//! the fastest call (the least disturbed on a shared machine).
//!
//! ```sh
//! cargo build --release -p occlude-moc --example moc_fill_calls
//! scripts/raster-icount.sh target/release/examples/moc_fill_calls 10 25
//! ```

use std::time::Instant;

use occlude_moc::{CullMode, MaskedBuffer};
use occlude_soft::workload;

fn main() {
    let (mut leg, mut calls, mut threads) = (25u32, 10usize, 1usize);
    let args: Vec<String> = std::env::args().skip(1).collect();
    for pair in args.chunks(2) {
        let value = pair.get(1).and_then(|v| v.parse::<usize>().ok()).filter(|&v| v >= 1);
        match (pair[0].as_str(), value) {
            ("--leg", Some(v)) => leg = v as u32,
            ("--calls", Some(v)) => calls = v,
            ("--threads", Some(v)) => threads = v,
            _ => {
                eprintln!("moc_fill_calls: expected --leg N, --calls K, --threads T (each at least 1)");
                std::process::exit(2);
            }
        }
    }
    let (w, h) = (1920, 1080);
    let count = workload::triangles_for_screens(w, h, leg, 2.0);
    let tris = workload::right_triangles(w, h, leg as f32, count);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool");
    let mut buffer = MaskedBuffer::new(w, h).expect("buffer");
    let mut fastest = f64::INFINITY;
    for _ in 0..calls {
        buffer.clear();
        let start = Instant::now();
        pool.install(|| buffer.render_clip_triangles(&tris, CullMode::None));
        fastest = fastest.min(start.elapsed().as_secs_f64());
    }
    println!(
        "moc {w}x{h}, N = {leg}, {threads} threads, {count} triangles per call: fastest of {calls} calls {:.3} ms, {:.3} MTris/s",
        fastest * 1e3,
        count as f64 / fastest / 1e6
    );
}
