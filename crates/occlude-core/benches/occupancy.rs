//! Throughput of the occupancy map of `om` (Staneker, Bartz, Straßer, section
//! 3.1) at its default resolution, 64 x 48 cells: rectangle tests per second
//! (`is_any_clear`, the stage-1 question for every node visited) on a map
//! about half covered by marks, for small and screen-sized rectangles.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use occlude_core::methods::om::occupancy::{CellRect, OccupancyBits};
use std::hint::black_box;

/// Small deterministic PRNG (splitmix64), so the workload needs no dependency.
struct SplitMix64(u64);

impl SplitMix64 {
    fn below(&mut self, n: u32) -> u32 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) % u64::from(n)) as u32
    }

    /// A rectangle of 1 to `max_side` cells a side, placed inside the map.
    fn rect(&mut self, map: &OccupancyBits, max_side: u32) -> CellRect {
        let (w, h) = (1 + self.below(max_side.min(map.width())), 1 + self.below(max_side.min(map.height())));
        let (x0, y0) = (self.below(map.width() - w + 1), self.below(map.height() - h + 1));
        CellRect { x0, y0, x1: x0 + w, y1: y0 + h }
    }
}

/// Rectangles tested per iteration.
const TESTS: usize = 4096;

fn test_throughput(c: &mut Criterion) {
    let mut group = c.benchmark_group("occupancy_test_64x48");
    group.throughput(Throughput::Elements(TESTS as u64));
    for max_side in [8u32, 64] {
        let mut rng = SplitMix64(u64::from(max_side));
        let mut map = OccupancyBits::new(64, 48);
        for _ in 0..24 {
            let r = rng.rect(&map, 16);
            map.mark(r);
        }
        let rects: Vec<CellRect> = (0..TESTS).map(|_| rng.rect(&map, max_side)).collect();
        group.bench_function(format!("is_any_clear_side_up_to_{max_side}"), |b| {
            b.iter(|| rects.iter().filter(|&&r| map.is_any_clear(black_box(r))).count())
        });
    }
    group.finish();
}

criterion_group!(benches, test_throughput);
criterion_main!(benches);
