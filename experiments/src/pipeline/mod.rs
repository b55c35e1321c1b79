//! What the `reproduce` driver alone uses: the jobs it runs ([`jobs`]), when a job may be
//! skipped ([`freshness`]), how they are run ([`schedule`]), the scorecard ([`scorecard`]), the
//! provenance page ([`provenance`]), the answer boxes that open the figure chapters
//! ([`answers`]), what the book takes from the own-device runs and the deviations study
//! ([`publish`]), the recorded definitive history match ([`recorded_history`]), the noise-level
//! curve read from the springs jobs' summaries after they ran ([`noise_curve`]), the
//! up-converter's comparison read from its jobs ([`upconversion`]), the Design chapter's
//! choice of optimiser read from its recorded comparison ([`design_optimisers`]) and the
//! book's build ([`book`]).

pub mod answers;
pub mod book;
pub mod design_optimisers;
pub mod freshness;
pub mod jobs;
pub mod noise_curve;
pub mod provenance;
pub mod publish;
pub mod recorded_history;
pub mod schedule;
pub mod scorecard;
pub mod upconversion;
