//! The helpers every report uses: plots drawn once into SVG and PNG ([`plot`]) with their legend
//! clear of the data ([`legend`]) and dense lines thinned to what their pixels show
//! ([`decimate`]), rows turned into typed data frames ([`frame`]) and Markdown tables ([`md`]),
//! progress bars ([`progress`]), an enlarged detail of a plot ([`zoom`]). Nothing here knows a
//! figure.

pub mod decimate;
pub mod frame;
pub mod legend;
pub mod md;
pub mod plot;
pub mod progress;
pub mod zoom;
