//! Granular visibility queries (Engelhardt and Dachsbacher, "Granular
//! Visibility Queries on the GPU"), section 3.1: pixel counting with summed
//! area tables, the CPU side and the CPU summed area table.
//!
//! Every frame, each query object's screen rectangle ([`PixelRect`]) and
//! its box's silhouette ([`Silhouette`]) are found; objects whose
//! rectangles overlap are in conflict ([`ConflictGraph`], section 3.1.1)
//! and the graph is coloured with the channels of the colour targets by the
//! paper's Chaitin-Briggs scheme. Objects the colouring cannot place
//! (conflict objects) have their rectangles split against the lookups
//! already made and merged again (section 3.1.2); where no channel is free,
//! the silhouettes tell the paper's three overlap configurations apart.
//! This gives each object a region set: rectangles with a channel each
//! ([`RegionPlan`]). Objects are rendered with, per pixel, the
//! channel of their region rectangle holding the pixel; a summed area table
//! per channel ([`SummedAreaTable`]) then answers each rectangle's pixel
//! count with four reads, and an object's count is the sum over its region
//! set.
//!
//! A colour `c` is component `c % 4` of target `c / 4`
//! ([`channel_target`]): more targets give more colours.

mod conflict;
mod rect;
mod region;
mod sat;
mod silhouette;

pub use conflict::{Colouring, ConflictGraph};
pub use rect::PixelRect;
pub use region::{plan, Lookup, PlanTimings, RegionMode, RegionPlan, RegionSet, SatConfig, MAX_TARGETS, NO_CHANNEL};
pub use sat::{count_errors, CountErrors, SummedAreaTable};
pub use silhouette::Silhouette;

/// Channels of one colour target (red, green, blue, alpha).
pub const CHANNELS_PER_TARGET: u32 = 4;

/// The colour target and its component (0 red to 3 alpha) that hold
/// colour `channel`.
pub fn channel_target(channel: u32) -> (u32, u32) {
    (channel / CHANNELS_PER_TARGET, channel % CHANNELS_PER_TARGET)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colours_fill_a_target_before_the_next() {
        assert_eq!(channel_target(0), (0, 0));
        assert_eq!(channel_target(3), (0, 3));
        assert_eq!(channel_target(4), (1, 0));
        assert_eq!(channel_target(31), (7, 3));
    }
}
