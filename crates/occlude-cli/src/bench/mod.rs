//! `occlude bench`'s output beside its tables and JSON: plots of a run
//! ([`plot`]) and of a paper's runs ([`paper_figures`]), and the frame
//! dumps ([`dump`]).

pub mod dump;
pub mod paper_figures;
pub mod plot;
