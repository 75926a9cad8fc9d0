//! The hierarchy's upkeep in a moving scene ([`occlude_core::motion`]): a
//! full binned-SAH BVH build of 100,000 scattered objects beside a refit of
//! the same tree after every object moved ([`SceneMotion`] with fraction 1)
//! and after a tenth of them moved. The refit alternates between two
//! frames' poses, so that every iteration changes every moved box.

use criterion::{criterion_group, criterion_main, Criterion};
use occlude_core::hierarchy::BuildOptions;
use occlude_core::{Hierarchy, HierarchyKind};
use occlude_scenes::scattered::scattered;
use occlude_scenes::SceneMotion;
use std::hint::black_box;

const OBJECTS: u32 = 100_000;

fn upkeep(c: &mut Criterion) {
    let scene = scattered(OBJECTS, 1);
    let mut group = c.benchmark_group("upkeep_100k");
    group.sample_size(20);
    group.bench_function("sah_build", |b| {
        b.iter(|| black_box(Hierarchy::build(&scene, HierarchyKind::Bvh, BuildOptions::default())))
    });
    for (name, fraction) in [("refit_all_moved", 1.0), ("refit_tenth_moved", 0.1)] {
        let motion = SceneMotion::new(&scene, fraction, 1);
        let frames: Vec<_> = [1.0, 2.0]
            .map(|t| {
                let mut s = scene.clone();
                let changed = s.apply(&motion.changes_at(t)).expect("finite motion");
                (s, changed)
            })
            .into();
        let mut h = Hierarchy::build(&scene, HierarchyKind::Bvh, BuildOptions::default());
        let mut k = 0;
        group.bench_function(name, |b| {
            b.iter(|| {
                let (s, changed) = &frames[k % 2];
                k += 1;
                h.refit(s, changed);
            })
        });
    }
    group.finish();
}

criterion_group!(benches, upkeep);
criterion_main!(benches);
