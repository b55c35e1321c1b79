//! Studies built on the model and the integrator: steady states under a sine ([`steady`]), the
//! stepped-drive engine ([`stepped`]) behind frequency sweeps ([`sweep`]) and amplitude sweeps
//! ([`amplitude`]), and random-vibration records ([`record`]) and their ensembles
//! ([`ensemble`]).

pub mod amplitude;
pub mod ensemble;
pub mod record;
pub mod steady;
pub mod stepped;
pub mod sweep;
