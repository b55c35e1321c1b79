//! The helpers every report uses: plots drawn once into SVG and PNG ([`plot`]), rows turned
//! into typed data frames ([`frame`]) and Markdown tables ([`md`]), progress bars
//! ([`progress`]), dense lines thinned to what their pixels show ([`decimate`]). Nothing here knows a figure.

pub mod decimate;
pub mod frame;
pub mod md;
pub mod plot;
pub mod progress;
