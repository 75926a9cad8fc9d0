//! Region sets (section 3.1.2): where to read the summed area tables for
//! each object's pixel count, and which channel each of its pixels is
//! rendered in.
//!
//! An object the colouring placed has one lookup, its whole rectangle in
//! its channel (until a later conflict object cuts a part it has no pixel
//! in out of it, below). A conflict object's rectangle is split against every lookup
//! made before it (figure 3 b, c): each piece keeps the channels the
//! lookups over it occupy; pieces sharing an edge are then merged while a
//! channel is free in both (figure 3 d), and each piece takes the lowest
//! channel free in it. Conflict objects are processed in index order, each
//! seeing the pieces of those before it. Splitting stops at
//! [`SatConfig::max_pieces`] pieces: further lookups then mark their
//! channel occupied in every piece they touch, unsplit (the paper's
//! abandoned split; less exact, never wrong).
//!
//! A piece with no free channel is first checked against the silhouettes
//! (section 3.1.2's three overlap configurations, [`Silhouette::meets`]).
//! If the object's own silhouette misses it ("empty overlap", or "overlap
//! no conflict" with only the others' pixels there), the object has no
//! pixel in it and it needs no lookup ([`RegionSet::outside`]). Else, if
//! some channel's lookups over it all belong to objects whose silhouettes
//! miss their overlap with it ("overlap no conflict"), those lookups are
//! split around the piece (their objects have no pixel there) and the piece
//! takes that channel, the lowest such, alone. Only what is left, both
//! objects meeting the overlap ("overlap conflict"), is where the two
//! [`RegionMode`]s differ: the conservative region set shares a channel
//! there (the pixels of both objects count for both, so a count is never
//! below the exact count), the approximate one leaves the
//! piece out (the object's pixels there are not rendered into any channel
//! and not counted: a count is never above the exact count, and no other
//! object's count is disturbed).
//!
//! Lookups that share no channel never overlap in one channel, so a
//! lookup holds, in its channel, only its own object's pixels and those of
//! shared lookups over it. An object with no piece shared or left out and
//! no shared lookup over its lookups is counted exactly
//! ([`RegionPlan::counted_exactly`]): its lookups hold all its pixels.

use super::conflict::{Colouring, ConflictGraph};
use super::rect::PixelRect;
use super::silhouette::Silhouette;
use super::CHANNELS_PER_TARGET;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Most colour targets (32 channels, one bit each in a `u32` mask).
pub const MAX_TARGETS: u32 = 8;

/// The channel of a pixel no lookup renders into (no object, or a piece an
/// approximate region set left out).
pub const NO_CHANNEL: u8 = u8::MAX;

/// What a region set does where no channel is free (module documentation).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RegionMode {
    /// Share a channel: counts never below the exact counts.
    #[default]
    Conservative,
    /// Leave the piece out: counts never above the exact counts.
    Approximate,
}

/// How region sets are built.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct SatConfig {
    /// Colour targets, 1 to [`MAX_TARGETS`]; 4 channels each.
    pub targets: u32,
    /// Sharing or leaving out where no channel is free.
    pub mode: RegionMode,
    /// Most pieces a conflict object is split into (at least 1).
    pub max_pieces: u32,
}

impl Default for SatConfig {
    fn default() -> Self {
        Self { targets: 1, mode: RegionMode::Conservative, max_pieces: 64 }
    }
}

impl SatConfig {
    /// Colours available: four per target.
    pub fn channels(&self) -> u32 {
        self.targets * CHANNELS_PER_TARGET
    }
}

/// One summed-area-table lookup: a rectangle read in one channel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Lookup {
    /// Pixels read.
    pub rect: PixelRect,
    /// Channel read (and rendered in by the object's pixels in `rect`).
    pub channel: u32,
    /// The channel was occupied by another object's lookup here (a
    /// conservative region set with no free channel).
    pub shared: bool,
}

/// One object's region set: disjoint lookups, left-out pieces and pieces
/// outside its silhouette that together tile its screen rectangle (empty
/// for an object off screen).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RegionSet {
    /// The lookups; the object's count is the sum of their reads.
    pub lookups: Vec<Lookup>,
    /// Pieces left out (approximate region sets only).
    pub dropped: Vec<PixelRect>,
    /// Pieces the object's silhouette misses ([`Silhouette::meets`]): it
    /// has no pixel there, so they need no lookup.
    pub outside: Vec<PixelRect>,
}

impl RegionSet {
    /// The channel the object's pixel `(x, y)` is rendered in, or
    /// [`NO_CHANNEL`] (what the paper's fragment shader decides per pixel).
    pub fn channel_at(&self, x: u32, y: u32) -> u8 {
        self.lookups.iter().find(|l| l.rect.contains(x, y)).map_or(NO_CHANNEL, |l| l.channel as u8)
    }
}

/// CPU time of the three steps, in milliseconds (Table 2's columns).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PlanTimings {
    /// The overlap test (building the conflict graph).
    pub overlap_ms: f64,
    /// The colouring.
    pub colouring_ms: f64,
    /// Split and merge of the conflict objects.
    pub split_merge_ms: f64,
}

/// The region sets of one frame's objects.
#[derive(Clone, Debug, PartialEq)]
pub struct RegionPlan {
    /// Per object, its region set.
    pub sets: Vec<RegionSet>,
    /// The colouring they came from.
    pub colouring: Colouring,
    /// Channels in use (the configuration's).
    pub channels: u32,
    /// Conflict objects (objects the colouring could not place).
    pub conflicts: u32,
    /// Lookups in all region sets.
    pub lookups: u32,
    /// Lookups sharing a channel.
    pub shared_lookups: u32,
    /// Time of each step.
    pub timings: PlanTimings,
}

impl RegionPlan {
    /// Whether object `v`'s count is exact (module documentation): none of
    /// its pieces shared or left out, and no other object's shared lookup
    /// over one of its lookups in the same channel.
    pub fn counted_exactly(&self, v: usize) -> bool {
        let set = &self.sets[v];
        let mixes = |l: &Lookup| {
            self.sets.iter().enumerate().any(|(w, other)| {
                w != v
                    && other
                        .lookups
                        .iter()
                        .any(|o| o.shared && o.channel == l.channel && o.rect.intersect(&l.rect).is_some())
            })
        };
        set.dropped.is_empty() && set.lookups.iter().all(|l| !l.shared && !mixes(l))
    }

    /// The channel image: per pixel of a `width`-wide image, the channel
    /// its owner (an object index into [`Self::sets`], or `u32::MAX` for
    /// none) renders it in.
    pub fn channel_image(&self, owners: &[u32], width: u32) -> Vec<u8> {
        let w = width.max(1) as usize;
        owners
            .iter()
            .enumerate()
            .map(|(p, &o)| match self.sets.get(o as usize) {
                Some(set) => set.channel_at((p % w) as u32, (p / w) as u32),
                None => NO_CHANNEL,
            })
            .collect()
    }
}

/// A piece of a conflict object's rectangle and the channels occupied in it.
#[derive(Clone, Copy, Debug)]
struct Piece {
    rect: PixelRect,
    occupied: u32,
}

/// The region sets of objects with screen silhouettes `shapes` (`None`:
/// off screen), built as the module documentation says.
///
/// # Panics
/// If `config.targets` is 0 or above [`MAX_TARGETS`].
pub fn plan(shapes: &[Option<Silhouette>], config: &SatConfig) -> RegionPlan {
    assert!((1..=MAX_TARGETS).contains(&config.targets), "{} targets: 1 to {MAX_TARGETS} supported", config.targets);
    let channels = config.channels();
    let all = if channels == 32 { u32::MAX } else { (1 << channels) - 1 };
    let rects: Vec<Option<PixelRect>> = shapes.iter().map(|s| s.map(|s| s.rect)).collect();

    let start = Instant::now();
    let graph = ConflictGraph::new(&rects);
    let overlap_ms = ms_since(start);

    let start = Instant::now();
    let colouring = graph.colour(channels);
    let colouring_ms = ms_since(start);

    let start = Instant::now();
    let mut sets = vec![RegionSet::default(); rects.len()];
    // Every lookup made so far, with the object it belongs to.
    let mut placed: Vec<(usize, Lookup)> = Vec::new();
    for (v, r) in rects.iter().enumerate() {
        if let (Some(rect), Some(channel)) = (r, colouring.colours[v]) {
            placed.push((v, Lookup { rect: *rect, channel, shared: false }));
        }
    }
    let conflicts = colouring.conflicts();
    for &v in &conflicts {
        let v = v as usize;
        let shape = shapes[v].expect("a conflict object has a rectangle");
        // The lookups over the rectangle, the only ones its pieces can
        // meet, as indices into `placed`.
        let mut near: Vec<usize> =
            (0..placed.len()).filter(|&k| placed[k].1.rect.intersect(&shape.rect).is_some()).collect();
        let over: Vec<Lookup> = near.iter().map(|&k| placed[k].1).collect();
        let mut pieces = split(shape.rect, &over, config.max_pieces as usize);
        merge(&mut pieces, all);
        for p in pieces {
            let free = all & !p.occupied;
            let lookup = if free != 0 {
                Lookup { rect: p.rect, channel: free.trailing_zeros(), shared: false }
            } else if !shape.meets(&p.rect) {
                // Empty overlap, or overlap no conflict with the others'
                // pixels alone: the object has none here.
                sets[v].outside.push(p.rect);
                continue;
            } else if let Some(channel) = clear_channel(&p.rect, &mut near, &mut placed, shapes, channels, &mut sets) {
                Lookup { rect: p.rect, channel, shared: false }
            } else if config.mode == RegionMode::Conservative {
                let channel = least_overlapped(&p.rect, near.iter().map(|&k| &placed[k].1), channels);
                Lookup { rect: p.rect, channel, shared: true }
            } else {
                sets[v].dropped.push(p.rect);
                continue;
            };
            placed.push((v, lookup));
        }
    }
    // Lookups cut away whole are left with an empty rectangle.
    placed.retain(|(_, l)| !l.rect.is_empty());
    for &(v, l) in &placed {
        sets[v].lookups.push(l);
    }
    let split_merge_ms = ms_since(start);

    RegionPlan {
        lookups: placed.len() as u32,
        shared_lookups: placed.iter().filter(|(_, l)| l.shared).count() as u32,
        sets,
        conflicts: conflicts.len() as u32,
        colouring,
        channels,
        timings: PlanTimings { overlap_ms, colouring_ms, split_merge_ms },
    }
}

/// Overlap no conflict (module documentation): the lowest channel whose
/// lookups over `rect` (among `placed`'s entries `near`) all belong to
/// objects whose silhouettes miss their overlap with it. Those lookups are
/// cut around `rect` (the parts cut off go to their objects'
/// [`RegionSet::outside`]; a lookup cut away whole keeps an empty
/// rectangle, the rest of one cut in several pieces joins `placed` and
/// `near`) and the channel is free in `rect`; `None` when no channel is.
fn clear_channel(
    rect: &PixelRect,
    near: &mut Vec<usize>,
    placed: &mut Vec<(usize, Lookup)>,
    shapes: &[Option<Silhouette>],
    channels: u32,
    sets: &mut [RegionSet],
) -> Option<u32> {
    let empty_of_owner = |c: u32| {
        near.iter()
            .map(|&k| placed[k])
            .filter(|(_, l)| l.channel == c)
            .all(|(w, l)| l.rect.intersect(rect).is_none_or(|i| shapes[w].is_some_and(|s| !s.meets(&i))))
    };
    let channel = (0..channels).find(|&c| empty_of_owner(c))?;
    for i in 0..near.len() {
        let k = near[i];
        let (w, l) = placed[k];
        let Some(cut) = l.rect.intersect(rect).filter(|_| l.channel == channel) else { continue };
        sets[w].outside.push(cut);
        let mut rest = l.rect.subtract(rect).into_iter();
        placed[k].1.rect = rest.next().unwrap_or_default();
        for r in rest {
            near.push(placed.len());
            placed.push((w, Lookup { rect: r, ..l }));
        }
    }
    Some(channel)
}

fn ms_since(start: Instant) -> f64 {
    start.elapsed().as_secs_f64() * 1e3
}

/// `rect` split against the lookups of `placed` (figure 3 b, c),
/// into at most `max_pieces` pieces (past that, lookups only mark the
/// pieces they touch).
fn split(rect: PixelRect, placed: &[Lookup], max_pieces: usize) -> Vec<Piece> {
    let mut pieces = vec![Piece { rect, occupied: 0 }];
    for l in placed {
        let bit = 1 << l.channel;
        let mut next = Vec::with_capacity(pieces.len() + 4);
        for p in pieces {
            match p.rect.intersect(&l.rect) {
                Some(inside) if p.occupied & bit == 0 => {
                    let rest = p.rect.subtract(&l.rect);
                    if next.len() + rest.len() + 1 > max_pieces.max(1) {
                        next.push(Piece { rect: p.rect, occupied: p.occupied | bit });
                    } else {
                        next.push(Piece { rect: inside, occupied: p.occupied | bit });
                        next.extend(rest.into_iter().map(|rect| Piece { rect, occupied: p.occupied }));
                    }
                }
                _ => next.push(p),
            }
        }
        pieces = next;
    }
    pieces
}

/// Merges pieces sharing an edge while a channel is free in both (figure
/// 3 d), until no pair can merge.
fn merge(pieces: &mut Vec<Piece>, all: u32) {
    'again: loop {
        for i in 0..pieces.len() {
            for j in i + 1..pieces.len() {
                let (a, b) = (pieces[i], pieces[j]);
                if all & !(a.occupied | b.occupied) == 0 {
                    continue;
                }
                if let Some(rect) = a.rect.join(&b.rect) {
                    pieces[i] = Piece { rect, occupied: a.occupied | b.occupied };
                    pieces.swap_remove(j);
                    continue 'again;
                }
            }
        }
        return;
    }
}

/// The channel whose lookups in `placed` cover the least of `rect` (the
/// lowest on ties): the one sharing costs the fewest foreign pixels at most.
fn least_overlapped<'a>(rect: &PixelRect, placed: impl Iterator<Item = &'a Lookup>, channels: u32) -> u32 {
    let mut overlap = vec![0u64; channels as usize];
    for l in placed {
        if let Some(i) = l.rect.intersect(rect) {
            overlap[l.channel as usize] += i.area();
        }
    }
    (0..channels).min_by_key(|&c| overlap[c as usize]).unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gvq::rect::tests::rect_strategy;
    use glam::DVec2;
    use proptest::prelude::*;

    /// Silhouettes known only by their rectangles.
    fn rectangles(rects: &[Option<PixelRect>]) -> Vec<Option<Silhouette>> {
        rects.iter().map(|r| r.map(Silhouette::rectangle)).collect()
    }

    fn config(targets: u32, mode: RegionMode, max_pieces: u32) -> SatConfig {
        SatConfig { targets, mode, max_pieces }
    }

    /// Whether `parts` tile `rect`: inside it, pairwise disjoint, areas summing to its area.
    fn tiles(rect: &PixelRect, parts: &[PixelRect]) -> bool {
        parts.iter().all(|p| p.intersect(rect) == Some(*p))
            && parts.iter().enumerate().all(|(i, p)| parts[i + 1..].iter().all(|q| p.intersect(q).is_none()))
            && parts.iter().map(PixelRect::area).sum::<u64>() == rect.area()
    }

    #[test]
    fn five_objects_on_one_spot_leave_one_conflict_sharing_a_channel() {
        let rects = vec![Some(PixelRect::new(0, 0, 10, 10)); 5];
        let p = plan(&rectangles(&rects), &SatConfig::default());
        assert_eq!(p.conflicts, 1);
        assert_eq!(p.shared_lookups, 1);
        let a = plan(&rectangles(&rects), &config(1, RegionMode::Approximate, 64));
        assert_eq!(a.shared_lookups, 0);
        assert_eq!(a.sets.iter().map(|s| s.dropped.len()).sum::<usize>(), 1);
        assert!(plan(&rectangles(&rects), &config(2, RegionMode::Conservative, 64)).conflicts == 0);
    }

    #[test]
    fn a_conflict_object_is_split_around_the_occupied_part() {
        // Four objects fill the left half of a fifth in every channel; the
        // fifth's right half is free and gets a lookup of its own. All five
        // tie on edges, so the lowest index is stacked first, reinserted
        // last and left without a channel.
        let mut rects = vec![Some(PixelRect::new(0, 0, 8, 4))];
        rects.extend(vec![Some(PixelRect::new(0, 0, 4, 4)); 4]);
        let p = plan(&rectangles(&rects), &SatConfig::default());
        assert_eq!(p.conflicts, 1);
        assert_eq!(p.colouring.conflicts(), vec![0]);
        let lookups = &p.sets[0].lookups;
        assert_eq!(lookups.len(), 2);
        assert!(lookups.iter().any(|l| l.rect == PixelRect::new(4, 0, 8, 4) && !l.shared));
        assert!(lookups.iter().any(|l| l.rect == PixelRect::new(0, 0, 4, 4) && l.shared));
    }

    #[test]
    fn overlaps_a_silhouette_misses_are_not_shared() {
        // Four objects on [8, 24)^2 are triangles in its bottom-right half
        // (x + y >= 32), missing the top-left quarter [8, 16)^2 that they
        // share with a fifth, object 0 on [0, 16)^2: a 5-clique on one
        // target, so object 0 is the conflict object and that quarter of
        // it has no free channel.
        let p = |x, y| DVec2::new(x, y);
        let triangle = |a: DVec2, b: DVec2, c: DVec2| [a, b, c, c, c, c, c, c];
        let bottom_right = triangle(p(24.0, 8.0), p(24.0, 24.0), p(8.0, 24.0));
        let others = Silhouette::outlined(PixelRect::new(8, 8, 24, 24), bottom_right);
        let overlap = PixelRect::new(8, 8, 16, 16);
        for mode in [RegionMode::Conservative, RegionMode::Approximate] {
            // Object 0 fills its rectangle: overlap no conflict. One of
            // the others' lookups is cut around the quarter, which object
            // 0 takes in that channel alone; every count is exact.
            let mut shapes = vec![Some(Silhouette::rectangle(PixelRect::new(0, 0, 16, 16)))];
            shapes.extend([Some(others); 4]);
            let regions = plan(&shapes, &config(1, mode, 64));
            assert_eq!(regions.colouring.conflicts(), vec![0]);
            assert_eq!(regions.shared_lookups, 0, "{mode:?}");
            assert!(regions.sets[0].dropped.is_empty());
            let mine = regions.sets[0].lookups.iter().find(|l| l.rect == overlap).expect("the quarter is looked up");
            let cut: Vec<usize> = (1..5).filter(|&w| regions.sets[w].outside == vec![overlap]).collect();
            assert_eq!(cut.len(), 1, "{mode:?}: one other object gives the quarter up");
            assert!(regions.sets[cut[0]].lookups.iter().all(|l| l.channel == mine.channel));
            assert!((0..5).all(|v| regions.counted_exactly(v)));
            // Object 0 a triangle in its top-left half (x + y <= 16):
            // empty overlap, the quarter is outside it and needs no lookup.
            let top_left = triangle(p(0.0, 0.0), p(16.0, 0.0), p(0.0, 16.0));
            shapes[0] = Some(Silhouette::outlined(PixelRect::new(0, 0, 16, 16), top_left));
            let regions = plan(&shapes, &config(1, mode, 64));
            assert_eq!(regions.shared_lookups, 0);
            assert_eq!(regions.sets[0].outside, vec![overlap]);
            assert!(regions.sets[0].lookups.iter().all(|l| l.rect.intersect(&overlap).is_none()));
            assert!((1..5).all(|w| regions.sets[w].outside.is_empty() && regions.sets[w].lookups.len() == 1));
        }
    }

    #[test]
    fn pieces_with_a_common_free_channel_merge_back_into_one() {
        // Two lookups in channel 0 cover the top and the bottom-left of a
        // rectangle: split, it is three pieces, all with channel 1 free.
        let lookup = |rect| Lookup { rect, channel: 0, shared: false };
        let placed = [lookup(PixelRect::new(0, 0, 10, 5)), lookup(PixelRect::new(0, 5, 3, 10))];
        let rect = PixelRect::new(0, 0, 10, 10);
        let mut pieces = split(rect, &placed, 64);
        assert_eq!(pieces.len(), 3);
        merge(&mut pieces, 0b11);
        assert_eq!(pieces.len(), 1);
        assert_eq!((pieces[0].rect, pieces[0].occupied), (rect, 0b01));
        // With channel 0 alone nothing is free in common: no merge.
        let mut pieces = split(rect, &placed, 64);
        merge(&mut pieces, 0b01);
        assert_eq!(pieces.len(), 3);
        // Past the piece limit, the lookups mark the piece unsplit.
        let pieces = split(rect, &placed, 1);
        assert_eq!(pieces.len(), 1);
        assert_eq!((pieces[0].rect, pieces[0].occupied), (rect, 0b01));
    }

    proptest! {
        #[test]
        fn region_sets_tile_each_rectangle_and_unshared_lookups_never_mix(
            rects in prop::collection::vec(rect_strategy(), 0..30),
            outlines in prop::collection::vec(prop::option::of(prop::array::uniform6(0.0f64..1.0)), 30),
            targets in 1u32..3,
            approximate in any::<bool>(),
            max_pieces in 1u32..80,
        ) {
            // Some objects' silhouettes are triangles in their rectangles
            // (`outlines`: the corners as fractions of its sides).
            let shapes: Vec<Option<Silhouette>> = rects
                .iter()
                .zip(&outlines)
                .map(|(r, t)| {
                    r.map(|r| match t {
                        None => Silhouette::rectangle(r),
                        Some(t) => {
                            let at = |fx: f64, fy: f64| {
                                DVec2::new(
                                    f64::from(r.x0) + fx * f64::from(r.x1 - r.x0),
                                    f64::from(r.y0) + fy * f64::from(r.y1 - r.y0),
                                )
                            };
                            let (a, b, c) = (at(t[0], t[1]), at(t[2], t[3]), at(t[4], t[5]));
                            Silhouette::outlined(r, [a, b, c, c, c, c, c, c])
                        }
                    })
                })
                .collect();
            let mode = if approximate { RegionMode::Approximate } else { RegionMode::Conservative };
            let p = plan(&shapes, &config(targets, mode, max_pieces));
            prop_assert_eq!(p.channels, 4 * targets);
            let mut all = Vec::new();
            for (v, r) in rects.iter().enumerate() {
                let set = &p.sets[v];
                let Some(r) = r else {
                    prop_assert!(set.lookups.is_empty() && set.dropped.is_empty());
                    continue;
                };
                let mut parts: Vec<_> = set.lookups.iter().map(|l| l.rect).collect();
                parts.extend(&set.dropped);
                parts.extend(&set.outside);
                let shape = shapes[v].expect("a rectangle");
                // No piece outside an object's silhouette can hold a pixel of it.
                prop_assert!(set.outside.iter().all(|o| !shape.meets(o)), "object {} outside {:?}", v, set.outside);
                // Rectangles alone never miss an overlap.
                prop_assert!(outlines[v].is_some() || set.outside.is_empty());
                prop_assert!(tiles(r, &parts), "object {} rect {:?} parts {:?}", v, r, parts);
                prop_assert!(mode == RegionMode::Approximate || set.dropped.is_empty());
                prop_assert!(mode == RegionMode::Conservative || set.lookups.iter().all(|l| !l.shared));
                prop_assert!(set.lookups.iter().all(|l| l.channel < p.channels));
                if p.colouring.colours[v].is_some() && set.outside.is_empty() {
                    prop_assert_eq!(set.lookups.len(), 1);
                }
                all.extend(set.lookups.iter().map(|l| (v, *l)));
            }
            for (i, (v, a)) in all.iter().enumerate() {
                for (w, b) in &all[i + 1..] {
                    if v != w && a.channel == b.channel && a.rect.intersect(&b.rect).is_some() {
                        prop_assert!(a.shared || b.shared, "{:?} of {} and {:?} of {} mix", a, v, b, w);
                    }
                }
            }
            prop_assert_eq!(p.conflicts as usize, p.colouring.conflicts().len());
        }
    }
}
